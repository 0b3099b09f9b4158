#pragma once
// File ▸ Session logs: the log folder's logs, newest first, with their sizes
// and times; replay one, or delete old ones (never the one being written).
//
// Thread: GUI thread only.

#include <QDialog>
#include <QString>

class QTreeWidget;

namespace sp {

class SessionLogsDialog : public QDialog {
  Q_OBJECT

 public:
  /// Lists `dir`; `current` is the log being written ("" = none).
  SessionLogsDialog(const QString& dir, const QString& current, QWidget* parent = nullptr);

 signals:
  /// The operator asked to replay the log at `path`.
  void replayRequested(const QString& path);

 private:
  void fill();
  void removeSelected();

  QString dir_, current_;
  QTreeWidget* list_ = nullptr;
};

}  // namespace sp
