#pragma once
// Robot > Connect: where the console's link goes. The robot's address
// (HOST:PORT, with the robots connected to before offered first), its
// token, or the stand-in on this machine. The addresses are remembered
// (QSettings "robots/recent", newest first, at most 10); tokens never are:
// they are secrets.
//
// Thread: GUI thread only.

#include <QDialog>
#include <QString>

#include <functional>
#include <QStringList>

class QComboBox;
class QLabel;
class QLineEdit;

namespace sp {

class ConnectDialog : public QDialog {
  Q_OBJECT

 public:
  /// `validate(hostPort, token)` returns "" or why the values cannot be
  /// used; the dialog stays open and shows why until they can.
  ConnectDialog(QWidget* parent, std::function<QString(const QString&, const QString&)> validate);

  QString hostPort() const;
  QString token() const;
  /// Whether the operator chose the stand-in instead of a robot.
  bool standIn() const { return standIn_; }

  /// The remembered addresses, newest first.
  static QStringList recentRobots();
  /// Puts `hostPort` first in the remembered addresses.
  static void remember(const QString& hostPort);

  // For tests.
  QComboBox* addressBox() const { return address_; }
  QLineEdit* tokenBox() const { return token_; }
  QString errorText() const;

 private:
  void tryAccept();

  std::function<QString(const QString&, const QString&)> validate_;
  QComboBox* address_ = nullptr;
  QLineEdit* token_ = nullptr;
  QLabel* error_ = nullptr;
  bool standIn_ = false;
};

}  // namespace sp
