#include "ui/connect_dialog.h"

#include <QComboBox>
#include <QDialogButtonBox>
#include <QFormLayout>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSettings>
#include <QVBoxLayout>

namespace sp {

namespace {
constexpr int kRecentMax = 10;
const QString kRecentKey = QStringLiteral("robots/recent");
}  // namespace

ConnectDialog::ConnectDialog(QWidget* parent, std::function<QString(const QString&, const QString&)> validate)
    : QDialog(parent), validate_(std::move(validate)) {
  setWindowTitle(tr("Connect to a robot"));
  setObjectName(QStringLiteral("connectDialog"));
  auto* layout = new QVBoxLayout(this);
  auto* form = new QFormLayout;
  address_ = new QComboBox;
  address_->setEditable(true);
  address_->addItems(recentRobots());
  address_->setCurrentText(address_->count() ? address_->itemText(0) : QStringLiteral("127.0.0.1:47800"));
  address_->setToolTip(tr("HOST:PORT of the robot (its port.robot); robots connected to before are in the list"));
  address_->setMinimumContentsLength(28);
  token_ = new QLineEdit;
  token_->setEchoMode(QLineEdit::Password);
  token_->setPlaceholderText(tr("32 or more hex digits"));
  token_->setToolTip(tr("The robot's shared secret. It never crosses the link (the robot's challenge is answered "
                        "with an HMAC of it) and is not remembered."));
  form->addRow(tr("robot"), address_);
  form->addRow(tr("token"), token_);
  layout->addLayout(form);
  error_ = new QLabel;
  error_->setObjectName(QStringLiteral("connectError"));
  error_->setStyleSheet(QStringLiteral("QLabel { color: #c62828; }"));
  error_->setWordWrap(true);
  error_->hide();
  layout->addWidget(error_);
  auto* buttons = new QDialogButtonBox;
  QPushButton* connectButton = buttons->addButton(tr("Connect"), QDialogButtonBox::AcceptRole);
  QPushButton* standIn = buttons->addButton(tr("Use the stand-in"), QDialogButtonBox::ActionRole);
  standIn->setToolTip(tr("Run the twin on this machine as the robot, in the world drawn now"));
  buttons->addButton(QDialogButtonBox::Cancel);
  connectButton->setDefault(true);
  layout->addWidget(buttons);
  connect(connectButton, &QPushButton::clicked, this, &ConnectDialog::tryAccept);
  connect(standIn, &QPushButton::clicked, this, [this] {
    standIn_ = true;
    accept();
  });
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
}

QString ConnectDialog::hostPort() const { return address_->currentText().trimmed(); }
QString ConnectDialog::token() const { return token_->text().trimmed(); }
QString ConnectDialog::errorText() const { return error_->isVisible() ? error_->text() : QString(); }

void ConnectDialog::tryAccept() {
  const QString why = validate_ ? validate_(hostPort(), token()) : QString();
  if (!why.isEmpty()) {
    error_->setText(why);
    error_->show();
    return;
  }
  standIn_ = false;
  accept();
}

QStringList ConnectDialog::recentRobots() { return QSettings().value(kRecentKey).toStringList(); }

void ConnectDialog::remember(const QString& hostPort) {
  QStringList recent = recentRobots();
  recent.removeAll(hostPort);
  recent.prepend(hostPort);
  while (recent.size() > kRecentMax) recent.removeLast();
  QSettings().setValue(kRecentKey, recent);
}

}  // namespace sp
