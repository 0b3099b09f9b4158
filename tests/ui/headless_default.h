#pragma once
// For widget tests that need no GL: before QTEST_MAIN's QApplication, with
// no display and no platform chosen, use the offscreen platform rather than
// let xcb abort, so a plain `ctest` in a headless container runs them too.
// An explicit QT_QPA_PLATFORM, or xvfb-run's DISPLAY, is left alone.

#include <QByteArray>
#include <QtGlobal>

namespace sp::test {

inline const bool kHeadlessDefault = [] {
  if (qEnvironmentVariableIsEmpty("DISPLAY") && qEnvironmentVariableIsEmpty("WAYLAND_DISPLAY") &&
      !qEnvironmentVariableIsSet("QT_QPA_PLATFORM")) {
    qputenv("QT_QPA_PLATFORM", QByteArrayLiteral("offscreen"));
    return true;
  }
  return false;
}();

}  // namespace sp::test
