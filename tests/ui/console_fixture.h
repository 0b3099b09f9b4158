#pragma once
// What the console's end-to-end tests share: settings and logs in a
// temporary folder, the window started on a world with its stand-in and
// shown at 1280x800, and a main() that asks for the GL 2.1 compatibility
// context OpenSceneGraph needs (shared/STACK.md).

#include <QApplication>
#include <QSettings>
#include <QTemporaryDir>
#include <QTest>

#include <memory>

#include "ui/main_window.h"
#include "ui/scene_view.h"

namespace sp::test {

/// Starts a console window on `world` with settings and logs under `dir`;
/// "" or what went wrong. `options` gets the world and log folder.
inline QString startConsole(const QTemporaryDir& dir, const QString& world, ConsoleOptions& options,
                            std::unique_ptr<MainWindow>& window) {
  QSettings::setDefaultFormat(QSettings::IniFormat);
  QSettings::setPath(QSettings::IniFormat, QSettings::UserScope, dir.filePath(QStringLiteral("settings")));
  QSettings().clear();
  options.world = world;
  options.logDir = dir.filePath(QStringLiteral("sessions"));
  window = std::make_unique<MainWindow>(options);
  const QString error = window->start();
  if (!error.isEmpty()) return error;
  window->resize(1280, 800);
  window->show();
  if (!QTest::qWaitForWindowExposed(window.get())) return QStringLiteral("the window was not exposed");
  return {};
}

/// main() of a GL test: the default surface format first, then the application.
template <typename Test>
int glTestMain(int argc, char** argv) {
  setSceneSurfaceFormat();
  QApplication app(argc, argv);
  Test test;
  return QTest::qExec(&test, argc, argv);
}

}  // namespace sp::test
