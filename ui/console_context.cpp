#include "ui/console_context.h"

#include <QMessageBox>
#include <QPushButton>

#include "app/console/console_session.h"
#include "app/console/terrain_editor.h"
#include "ui/scene_view.h"
#include "ui/robot_connection.h"

namespace sp {

namespace {

constexpr size_t kPartHeights = 2000;  // a terrain patch's heights per COMMAND: fits a 64 KiB frame

}  // namespace

ConsoleContext::ConsoleContext(Parts parts, QObject* parent) : QObject(parent), parts_(std::move(parts)) {
  connect(parts_.connection, &RobotConnection::sequenceState, this, &ConsoleContext::sequenceState);
  connect(parts_.connection, &RobotConnection::guardTripped, this, &ConsoleContext::guardTripped);
}

LiveCalibrator* ConsoleContext::calibrator() const { return parts_.session->calibrator(); }
TerrainEditor* ConsoleContext::terrainEditor() const { return parts_.session->terrainEditor(); }
std::string ConsoleContext::useStandIn() { return parts_.session->useStandIn(); }
std::string ConsoleContext::connectTo(const std::string& hostPort, const std::string& token) {
  return parts_.session->connectTo(hostPort, token);
}
std::string ConsoleContext::resetRobot() { return parts_.session->resetRobot(); }

std::string ConsoleContext::sinkRefusal() const {
  // A replay shown is not the robot the operator means: nothing goes out.
  return state().replaying() ? state().controlsRefusal() : session().commandRefusal(state().leaseHeld());
}

bool ConsoleContext::editTerrain(const TerrainPatchCmd& patch) {
  if (state().replaying()) return false;  // the view shows the log's world
  if (!parts_.session->terrainEdited(patch)) return false;
  scene().applyTerrainPatch(patch);
  emit terrainEdited(patch);
  if (robotTakesTerrainEdits() && state().leaseHeld())
    for (const TerrainPatchCmd& part : splitPatch(patch, kPartHeights)) connection().send(part, session().robot());
  return true;
}

bool ConsoleContext::robotTakesTerrainEdits() const {
  if (!state().connected()) return false;
  const std::string caps = " " + connection().stats().robotCapabilities + " ";
  return caps.find(" terrain_edit ") != std::string::npos;
}

QString ConsoleContext::sendSequence(const net::SequenceMsg& message) {
  if (const std::string why = sinkRefusal(); !why.empty()) return QString::fromStdString(why);
  connection().sendSequence(message);
  return {};
}

void ConsoleContext::abortSequence(const QString& hash, const QString& reason) {
  connection().abortSequence(hash, reason);
}

const std::shared_ptr<SequenceGuard>& ConsoleContext::guard() const { return connection().guard(); }

QString ConsoleContext::sendCommand(const Command& command) {
  if (const std::string why = sinkRefusal(); !why.empty()) {
    const QString text = QString::fromStdString(why);
    status(text, 4000);
    return text;
  }
  connection().send(command, session().robot());
  parts_.session->commandSent(command);
  return {};
}

void ConsoleContext::event(const QString& kind, const QString& text, bool log) {
  if (log) parts_.session->event(kind.toStdString(), text.toStdString());
  emit eventShown(text);
}

void ConsoleContext::emergencyStop() {
  // Said as it is: sent only when the link is up (a client still trying
  // to reconnect sends it once the robot welcomes it again).
  const bool queued = connection().isOpen();
  const QString text = QString::fromStdString(state().estopPressedText(queued));
  connection().estop(tr("operator e-stop"));
  event(QStringLiteral("estop"), text);
  status(text, 5000);
}

void ConsoleContext::logEvent(const QString& kind, const QString& text) const {
  parts_.session->logEvent(kind.toStdString(), text.toStdString());
}

bool ConsoleContext::confirm(QMessageBox::Icon icon, const QString& title, const QString& text,
                             const QString& objectName, const QString& yes, QMessageBox::ButtonRole role) const {
  QMessageBox box(icon, title, text, QMessageBox::NoButton, dialogParent());
  box.setObjectName(objectName);
  QPushButton* accept = box.addButton(yes, role);
  box.setDefaultButton(box.addButton(tr("Cancel"), QMessageBox::RejectRole));
  box.exec();
  return box.clickedButton() == accept;
}

void ConsoleContext::showError(const QString& title, const QString& text) const {
  QMessageBox box(QMessageBox::Warning, title, title + tr(". The running session is unchanged."), QMessageBox::Ok,
                  dialogParent());
  box.setDetailedText(text);
  box.setInformativeText(text.section(QLatin1Char('\n'), 0, 4));
  box.exec();
}

}  // namespace sp
