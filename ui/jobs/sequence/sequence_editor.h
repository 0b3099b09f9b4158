#pragma once
// The Sequence dock's editor (ui/jobs/sequence/sequence_panel.h): the
// `.seq` text in a fixed font, Open…, Save… and a template per command
// (Insert), and the text's problems inline: each line underlined with its
// message as a tooltip, and listed below (a click goes to the line).
//
// Thread: GUI thread.

#include <QList>
#include <QString>
#include <QWidget>

#include <vector>

#include "app/rehearse/sequence_workflow.h"

class QListWidget;
class QPlainTextEdit;
class QTimer;
class QToolButton;

namespace sp {

class SequenceEditor : public QWidget {
  Q_OBJECT

 public:
  explicit SequenceEditor(QWidget* parent = nullptr);

  QString text() const;
  void setText(const QString& text);
  /// Marks `problems` in the text and lists them; none: the list hides.
  void showProblems(const std::vector<SequenceWorkflow::Problem>& problems);
  /// The lines marked in the text.
  QList<int> markedLines() const { return marked_; }
  /// The problems as listed, "line N: message" each.
  QStringList problemTexts() const { return listed_; }
  /// A check is due no more (the caller checks now).
  void checkStarted();

 signals:
  /// The text changed (every key).
  void edited();
  /// 150 ms after the last key: time to check the text.
  void checkDue();

 private:
  void buildTemplateMenu(QToolButton* button);
  void openFile();
  void saveFile();

  QPlainTextEdit* editor_ = nullptr;
  QListWidget* problemList_ = nullptr;
  QTimer* checkTimer_ = nullptr;
  QList<int> marked_;
  QStringList listed_;
};

}  // namespace sp
