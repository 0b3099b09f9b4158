#pragma once
// What the console's end-to-end tests share: settings and logs in a
// temporary folder, the window started on a world with its stand-in and
// shown at 1280x800, and a main() that asks for the GL 2.1 compatibility
// context OpenSceneGraph needs (shared/STACK.md).

#include <QApplication>
#include <QCommandLineParser>
#include <QSettings>
#include <QTemporaryDir>
#include <QTest>

#include <memory>

#include "ui/jobs/drive/drive_job.h"
#include "ui/jobs/jobs.h"
#include "ui/jobs/link/link_job.h"
#include "ui/jobs/replay/replay_job.h"
#include "ui/jobs/sequence/sequence_job.h"
#include "ui/jobs/terrain/terrain_job.h"
#include "ui/main_window.h"
#include "ui/scene_view.h"

namespace sp::test {

/// The built-in jobs, having taken `arguments` (their own options only,
/// e.g. {"--monitor"}) as the console's command line hands them; a parse
/// error or a job's complaint fails the test that asked.
inline ConsoleJobs jobsWith(const QStringList& arguments) {
  ConsoleJobs jobs = builtInJobs();
  QCommandLineParser parser;
  addJobOptions(parser, jobs);
  if (!parser.parse(QStringList{QStringLiteral("simpartner")} + arguments))
    qFatal("jobsWith: %s", qPrintable(parser.errorText()));
  if (const QString error = takeJobOptions(parser, jobs); !error.isEmpty()) qFatal("jobsWith: %s", qPrintable(error));
  return jobs;
}

/// Starts a console window on `world` with settings and logs under `dir`
/// and `jobs` installed; "" or what went wrong. `options` gets the world
/// and log folder.
inline QString startConsole(const QTemporaryDir& dir, const QString& world, ConsoleOptions& options,
                            std::unique_ptr<MainWindow>& window, ConsoleJobs jobs) {
  QSettings::setDefaultFormat(QSettings::IniFormat);
  QSettings::setPath(QSettings::IniFormat, QSettings::UserScope, dir.filePath(QStringLiteral("settings")));
  QSettings().clear();
  options.world = world;
  options.logDir = dir.filePath(QStringLiteral("sessions"));
  window = std::make_unique<MainWindow>(options, std::move(jobs));
  const QString error = window->start();
  if (!error.isEmpty()) return error;
  window->resize(1280, 800);
  window->show();
  if (!QTest::qWaitForWindowExposed(window.get())) return QStringLiteral("the window was not exposed");
  return {};
}

/// The same with the built-in jobs, given `jobArguments`.
inline QString startConsole(const QTemporaryDir& dir, const QString& world, ConsoleOptions& options,
                            std::unique_ptr<MainWindow>& window, const QStringList& jobArguments = {}) {
  return startConsole(dir, world, options, window, jobsWith(jobArguments));
}

/// main() of a GL test: the default surface format first, then the application.
template <typename Test>
int glTestMain(int argc, char** argv) {
  setSceneSurfaceFormat();
  QApplication app(argc, argv);
  Test test;
  return QTest::qExec(&test, argc, argv);
}

// The built-in jobs' panels and doings, as the tests reach them: through
// the jobs installed in the window (MainWindow knows no job).
inline LinkPanel* linkPanel(const MainWindow& w) { return w.job<LinkJob>()->panel(); }
inline ControlPanel* controlPanel(const MainWindow& w) {
  DriveJob* j = w.job<DriveJob>();
  return j ? j->panel() : nullptr;
}
inline SequencePanel* sequencePanel(const MainWindow& w) {
  SequenceJob* j = w.job<SequenceJob>();
  return j ? j->panel() : nullptr;
}
inline TerrainPanel* terrainPanel(const MainWindow& w) {
  TerrainJob* j = w.job<TerrainJob>();
  return j ? j->panel() : nullptr;
}
inline ReplayPanel* replayPanel(const MainWindow& w) {
  ReplayJob* j = w.job<ReplayJob>();
  return j ? j->panel() : nullptr;
}
/// Terrain edits applied since the start (each dab, undo or redo).
inline int64_t terrainEdits(const MainWindow& w) { return w.job<TerrainJob>()->edits(); }
/// File ▸ Open session log: "" or why not (in a dialog unless `quiet`).
inline QString openLog(const MainWindow& w, const QString& path, bool quiet = false) {
  return w.job<ReplayJob>()->openLog(path, quiet);
}
inline void openLogInBackground(const MainWindow& w, const QString& path) { w.job<ReplayJob>()->openLogInBackground(path); }
inline void showSessionLogs(const MainWindow& w) { w.job<ReplayJob>()->showSessionLogs(); }
inline QStringList recentLogs(const MainWindow& w) { return w.job<ReplayJob>()->recentLogs(); }
inline void rearm(const MainWindow& w) { w.job<LinkJob>()->rearm(); }
inline void openConnectDialog(const MainWindow& w) { w.job<LinkJob>()->openConnectDialog(); }
inline void resetRobot(const MainWindow& w) { w.job<LinkJob>()->resetRobot(); }

}  // namespace sp::test
