#include "ui/jobs/replay/session_logs_dialog.h"

#include <QDateTime>
#include <QDialogButtonBox>
#include <QFileInfo>
#include <QLabel>
#include <QMessageBox>
#include <QPushButton>
#include <QTreeWidget>
#include <QVBoxLayout>

#include "app/log/session_recorder.h"

namespace sp {

SessionLogsDialog::SessionLogsDialog(const QString& dir, const QString& current, QWidget* parent)
    : QDialog(parent), dir_(dir), current_(current) {
  setWindowTitle(tr("Session logs"));
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(new QLabel(tr("In %1 (parameter log.keep: how many are kept)").arg(dir), this));
  list_ = new QTreeWidget(this);
  list_->setHeaderLabels({tr("Log"), tr("Size"), tr("Written")});
  list_->setRootIsDecorated(false);
  list_->setSelectionMode(QAbstractItemView::ExtendedSelection);
  layout->addWidget(list_);
  fill();
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, this);
  QPushButton* open = buttons->addButton(tr("Replay"), QDialogButtonBox::ActionRole);
  QPushButton* remove = buttons->addButton(tr("Delete…"), QDialogButtonBox::ActionRole);
  layout->addWidget(buttons);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  connect(open, &QPushButton::clicked, this, [this] {
    if (QTreeWidgetItem* item = list_->currentItem()) {
      emit replayRequested(item->data(0, Qt::UserRole).toString());
      accept();
    }
  });
  connect(remove, &QPushButton::clicked, this, &SessionLogsDialog::removeSelected);
  resize(640, 400);
}

void SessionLogsDialog::fill() {
  list_->clear();
  for (const SessionLogFile& f : listSessionLogs(dir_.toStdString())) {
    const QString path = QString::fromStdString(f.path);
    auto* item = new QTreeWidgetItem(list_, {QFileInfo(path).fileName(),
                                             QStringLiteral("%1 MB").arg(static_cast<double>(f.bytes) / 1e6, 0, 'f', 1),
                                             QDateTime::fromSecsSinceEpoch(f.modified).toString(Qt::ISODate)});
    item->setData(0, Qt::UserRole, path);
    if (path == current_) item->setText(0, item->text(0) + tr(" (this session)"));
  }
  for (int c = 0; c < 3; ++c) list_->resizeColumnToContents(c);
}

void SessionLogsDialog::removeSelected() {
  QStringList paths;
  for (QTreeWidgetItem* item : list_->selectedItems())
    if (item->data(0, Qt::UserRole).toString() != current_) paths << item->data(0, Qt::UserRole).toString();
  if (paths.isEmpty()) return;
  if (QMessageBox::question(this, tr("Delete session logs"),
                            tr("Delete %n log(s)? This cannot be undone.", "", static_cast<int>(paths.size())),
                            QMessageBox::Yes | QMessageBox::Cancel, QMessageBox::Cancel) != QMessageBox::Yes)
    return;
  for (const QString& p : paths)
    if (const std::string e = deleteSessionLog(p.toStdString()); !e.empty())
      QMessageBox::warning(this, tr("Delete"), QString::fromStdString(e));
  fill();
}

}  // namespace sp
