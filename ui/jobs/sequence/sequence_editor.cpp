#include "ui/jobs/sequence/sequence_editor.h"

#include <QBoxLayout>
#include <QFile>
#include <QFileDialog>
#include <QFontDatabase>
#include <QListWidget>
#include <QMenu>
#include <QMessageBox>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QTextBlock>
#include <QTimer>
#include <QToolButton>

#include <algorithm>

namespace sp {

namespace {

// One line per command of docs/formats.md, with what its numbers mean.
struct Template {
  const char* label;
  const char* text;  // after the time
};
constexpr Template kTemplates[] = {
    {"drive: roll with the hinge at an angle", "drive 0.5 0        # speed [m/s], articulation [deg]"},
    {"turn: roll at a yaw rate", "turn 0.5 10        # speed [m/s], yaw rate [deg/s], > 0 left"},
    {"wheels: four wheel speeds", "wheels 2 2 2 2     # FL FR RL RR [rad/s]"},
    {"target: a joint to an angle", "target waist_yaw 0 # joint, angle [deg] (slider: [m])"},
    {"velocity: a joint at a speed", "velocity waist_yaw 10  # joint, [deg/s] (slider: [m/s])"},
    {"torque: a joint's torque", "torque waist_yaw 0 # joint, [N m] (slider: [N])"},
    {"mode: switch a joint's mode", "mode waist_yaw position  # velocity, position, torque, free"},
    {"gait: caterpillar, rolking or off", "gait caterpillar"},
    {"stop: brake and hold", "stop"},
};

}  // namespace

SequenceEditor::SequenceEditor(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->setSpacing(3);
  auto* fileRow = new QHBoxLayout;
  auto* open = new QPushButton(tr("Open…"), this);
  auto* save = new QPushButton(tr("Save…"), this);
  auto* insert = new QToolButton(this);
  insert->setText(tr("Insert"));
  insert->setToolTip(tr("Insert a command at the cursor, with what its numbers mean"));
  buildTemplateMenu(insert);
  fileRow->addWidget(open);
  fileRow->addWidget(save);
  fileRow->addWidget(insert);
  fileRow->addStretch();
  layout->addLayout(fileRow);
  connect(open, &QPushButton::clicked, this, &SequenceEditor::openFile);
  connect(save, &QPushButton::clicked, this, &SequenceEditor::saveFile);

  editor_ = new QPlainTextEdit(this);
  editor_->setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
  editor_->setPlaceholderText(tr("# time [s]  command  arguments\n1.0  drive 0.5 0\n5.0  stop"));
  editor_->setLineWrapMode(QPlainTextEdit::NoWrap);
  editor_->setMinimumHeight(48);
  layout->addWidget(editor_, 1);
  problemList_ = new QListWidget(this);
  problemList_->setMaximumHeight(70);
  problemList_->hide();
  layout->addWidget(problemList_);
  // Checked 150 ms after the last key, not on every key.
  checkTimer_ = new QTimer(this);
  checkTimer_->setSingleShot(true);
  checkTimer_->setInterval(150);
  connect(checkTimer_, &QTimer::timeout, this, &SequenceEditor::checkDue);
  connect(editor_, &QPlainTextEdit::textChanged, this, [this] {
    checkTimer_->start();
    emit edited();
  });
  connect(problemList_, &QListWidget::itemActivated, this, [this](QListWidgetItem* item) {
    const int line = item->data(Qt::UserRole).toInt();
    const QTextBlock block = editor_->document()->findBlockByNumber(line - 1);
    if (!block.isValid()) return;
    editor_->setTextCursor(QTextCursor(block));
    editor_->setFocus();
  });
}

QString SequenceEditor::text() const { return editor_->toPlainText(); }

void SequenceEditor::setText(const QString& text) { editor_->setPlainText(text); }

void SequenceEditor::checkStarted() { checkTimer_->stop(); }

void SequenceEditor::showProblems(const std::vector<SequenceWorkflow::Problem>& problems) {
  marked_.clear();
  listed_.clear();
  problemList_->clear();
  QList<QTextEdit::ExtraSelection> marks;
  for (const SequenceWorkflow::Problem& p : problems) {
    const QString message = QString::fromStdString(p.message);
    listed_ << QStringLiteral("line %1: %2").arg(p.line).arg(message);
    auto* item = new QListWidgetItem(listed_.back(), problemList_);
    item->setData(Qt::UserRole, p.line);
    item->setForeground(QColor(170, 0, 0));
    if (p.line <= 0 || marked_.contains(p.line)) continue;
    marked_ << p.line;
    QTextEdit::ExtraSelection mark;
    mark.cursor = QTextCursor(editor_->document()->findBlockByNumber(p.line - 1));
    mark.format.setBackground(QColor(255, 225, 225));
    mark.format.setUnderlineStyle(QTextCharFormat::WaveUnderline);
    mark.format.setUnderlineColor(Qt::red);
    mark.format.setProperty(QTextFormat::FullWidthSelection, true);
    mark.format.setToolTip(message);
    marks << mark;
  }
  editor_->setExtraSelections(marks);
  problemList_->setVisible(!listed_.isEmpty());
  // As tall as its lines, three at most: 70 px for one error squeezed the
  // editor to two lines (issue 59).
  if (problemList_->count() > 0)
    problemList_->setFixedHeight(std::min(3, problemList_->count()) * problemList_->sizeHintForRow(0) +
                                 2 * problemList_->frameWidth());
}

void SequenceEditor::buildTemplateMenu(QToolButton* button) {
  auto* menu = new QMenu(button);
  for (const Template& t : kTemplates) {
    menu->addAction(QString::fromUtf8(t.label), this, [this, text = QString::fromUtf8(t.text)] {
      // At the line after the cursor's, a second after the last time above it.
      double last = -1;
      const int here = editor_->textCursor().blockNumber();
      for (QTextBlock b = editor_->document()->begin(); b.isValid() && b.blockNumber() <= here; b = b.next()) {
        bool ok = false;
        const double t0 = b.text().section(' ', 0, 0, QString::SectionSkipEmpty).toDouble(&ok);
        if (ok) last = t0;
      }
      QTextCursor c = editor_->textCursor();
      c.movePosition(QTextCursor::EndOfBlock);
      const QString line = QString::number(last < 0 ? 0.0 : last + 1.0, 'f', 1) + "  " + text;
      c.insertText(editor_->document()->isEmpty() ? line : "\n" + line);
      editor_->setTextCursor(c);
    });
  }
  button->setMenu(menu);
  button->setPopupMode(QToolButton::InstantPopup);
}

void SequenceEditor::openFile() {
  const QString path = QFileDialog::getOpenFileName(this, tr("Open sequence"), QString(), tr("Sequences (*.seq);;All files (*)"));
  if (path.isEmpty()) return;
  QFile f(path);
  if (!f.open(QIODevice::ReadOnly) || f.size() > 1 << 20) {
    QMessageBox::warning(this, tr("Open sequence"), tr("%1: cannot read (or larger than 1 MiB)").arg(path));
    return;
  }
  setText(QString::fromUtf8(f.readAll()));
}

void SequenceEditor::saveFile() {
  const QString path = QFileDialog::getSaveFileName(this, tr("Save sequence"), QString(), tr("Sequences (*.seq)"));
  if (path.isEmpty()) return;
  QFile f(path);
  if (!f.open(QIODevice::WriteOnly | QIODevice::Truncate) || f.write(editor_->toPlainText().toUtf8()) < 0 ||
      !f.flush()) {
    QMessageBox::warning(this, tr("Save sequence"), tr("%1: %2").arg(path, f.errorString()));
  }
}

}  // namespace sp
