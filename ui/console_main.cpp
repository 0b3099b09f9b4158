// simpartner: the operator console. Opens the main window on a world, starts
// the stand-in robot on loopback (or connects to a robot with --connect) and
// logs the session.

#include <QApplication>
#include <QCommandLineParser>
#include <QDir>
#include <QElapsedTimer>
#include <QMessageBox>
#include <QRegularExpression>
#include <QTimer>

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "app/console/console_session.h"
#include "app/data/data_files.h"
#include "ui/icons.h"
#include "ui/live_plots.h"
#include "ui/jobs/jobs.h"
#include "ui/main_window.h"
#include "ui/scene_view.h"

namespace {

/// The value of a numeric option, or nullopt after saying on stderr what is
/// wrong with it (`<command line>: error: --OPTION: ...`).
std::optional<double> numberOption(const QCommandLineParser& parser, const QCommandLineOption& option, double min,
                                   double max) {
  bool ok = false;
  const QString text = parser.value(option);
  const double value = text.toDouble(&ok);
  if (ok && value >= min && value <= max) return value;
  std::cerr << "<command line>: error: --" << option.names().constLast().toStdString() << ": expected a number in ["
            << min << ", " << max << "], got '" << text.toStdString() << "'\n";
  return std::nullopt;
}

// The console's own options; each job declares its own (ui/jobs/jobs.h).
struct ConsoleFlags {
  static QCommandLineOption valued(const QStringList& names, const char* help, const char* value,
                                   const QString& byDefault = {}) {
    return QCommandLineOption(names, QString::fromUtf8(help), QString::fromUtf8(value), byDefault);
  }
  static QCommandLineOption flag(const char* name, const char* help) {
    return QCommandLineOption(QString::fromUtf8(name), QString::fromUtf8(help));
  }
  QCommandLineOption world = valued({QStringLiteral("w"), QStringLiteral("world")}, "World file (default terrains/flat.world.xml).",
                                    "FILE", QStringLiteral("terrains/flat.world.xml"));
  QCommandLineOption params = valued({QStringLiteral("params")}, "Parameters file for the stand-in.", "FILE");
  QCommandLineOption set = valued({QStringLiteral("set")}, "Parameter override KEY=VALUE (repeatable).", "KEY=VALUE");
  QCommandLineOption connectTo = valued({QStringLiteral("connect")},
                                        "Connect to the robot at HOST:PORT instead of starting the stand-in.", "HOST:PORT");
  QCommandLineOption token = valued({QStringLiteral("token")}, "The robot's shared secret (32+ hex digits).", "HEX");
  QCommandLineOption logDir = valued({QStringLiteral("log-dir")}, "Folder for session logs (default: the user's data folder).", "DIR");
  QCommandLineOption noLog = flag("no-log", "Do not log the session.");
  QCommandLineOption rtf = valued({QStringLiteral("rtf")}, "Stand-in real-time factor.", "X");
  QCommandLineOption screenshot = valued({QStringLiteral("screenshot")},
                                         "Save a picture of the window after --quit-after seconds, then quit.", "PNG");
  QCommandLineOption quitAfter = valued({QStringLiteral("quit-after")},
                                        "Quit after S seconds, printing the frame rate (for measurements).", "S");
  QCommandLineOption delay = valued({QStringLiteral("delay")},
                                    "The stand-in's link delays every frame by S seconds each way (rehearse a slow link; "
                                    "the ghost spans it).", "S");
  QCommandLineOption perturb = valued({QStringLiteral("perturb")},
                                      "The stand-in is a robot that is not its twin: hidden deviations from the files drawn "
                                      "from SEED (simpartner-robot --help lists them).", "SEED");
  QCommandLineOption ground = valued({QStringLiteral("ground")},
                                     "The stand-in stands on FILE's terrain, not the drawn world's: ground the "
                                     "console's map lacks (terrains/rough_unmapped.world.xml beside --world "
                                     "terrains/rough.world.xml).", "FILE");
  QCommandLineOption noGhost = flag("no-ghost", "Do not run the predictive ghost.");
  QCommandLineOption noCalibration = flag("no-calibration", "Do not calibrate the twin from telemetry while driving.");
  QCommandLineOption errorDialog = flag("error-dialog",
                                        "Show an error that stops the start in a dialog too (the desktop entry sets it: no "
                                        "terminal shows stderr there).");
  QList<QCommandLineOption> all() const {
    return {errorDialog, world, params, set, connectTo, token, logDir, noLog, rtf, delay, perturb, ground, noGhost,
            noCalibration, screenshot, quitAfter};
  }
};

// What the command line asks of a start.
struct Start {
  sp::ConsoleOptions options;
  QString startError;  // a file not found: said once the application exists (a dialog needs it)
  std::optional<double> quitSeconds;
};

// A token that the robot can only refuse is refused here, at once, rather
// than after a connection attempt. Exit code 2, or nullopt when fine.
std::optional<int> checkToken(const QString& t) {
  static const QRegularExpression hex(QStringLiteral("^[0-9a-fA-F]*$"));
  if (hex.match(t).hasMatch() && t.size() >= 32) return std::nullopt;
  std::cerr << "<command line>: error: --token: expected at least 32 hex digits (128 bits), got "
            << (hex.match(t).hasMatch() ? std::to_string(t.size()) + " digits" : std::string("other characters")) << "\n";
  return 2;
}

// The console's options and the jobs' from a parsed command line into
// `start`; an exit code when the command line is wrong.
std::optional<int> readOptions(const QCommandLineParser& parser, const ConsoleFlags& f, sp::ConsoleJobs& jobs, Start& start) {
  if (parser.isSet(f.token))
    if (const auto exit = checkToken(parser.value(f.token))) return exit;
  // Files named relative to the data folder (terrains/..., robots/...) are
  // found there from any working directory (app/data/data_files.h).
  const auto findDataFile = [&start](const QString& path) {
    std::string error;
    const std::string found = sp::findDataFile(path.toStdString(), error);
    if (!error.empty() && start.startError.isEmpty()) start.startError = QString::fromStdString(error);
    return QString::fromStdString(found);
  };
  sp::ConsoleOptions& options = start.options;
  options.world = findDataFile(parser.value(f.world));
  options.params = findDataFile(parser.value(f.params));
  options.overrides = parser.values(f.set);
  options.connectTo = parser.value(f.connectTo);
  options.token = parser.value(f.token);
  options.logDir = parser.value(f.logDir);
  options.log = !parser.isSet(f.noLog);
  // A job's bad option value is a command-line error (exit 2, as every
  // other one); a file it names not found stops the start as ours do.
  if (const QString error = sp::takeJobOptions(parser, jobs); !error.isEmpty()) {
    if (error.startsWith(QLatin1String("<command line>:"))) {
      std::cerr << error.toStdString() << "\n";
      return 2;
    }
    if (start.startError.isEmpty()) start.startError = error;
  }
  if (parser.isSet(f.rtf)) {
    const std::optional<double> x = numberOption(parser, f.rtf, 0, 1000);
    if (!x) return 2;
    options.rtf = *x;
  }
  if (parser.isSet(f.delay)) {
    const std::optional<double> s = numberOption(parser, f.delay, 0, 60);
    if (!s) return 2;
    options.delay = *s;
  }
  if (parser.isSet(f.perturb)) {
    bool ok = false;
    const qulonglong seed = parser.value(f.perturb).toULongLong(&ok);
    if (!ok) {
      std::cerr << "<command line>: error: --perturb: expected a seed (an unsigned integer), got '"
                << parser.value(f.perturb).toStdString() << "'\n";
      return 2;
    }
    options.perturbSeed = seed;
    if (!options.connectTo.isEmpty()) {
      std::cerr << "<command line>: error: --perturb changes the built-in stand-in; it does not go with --connect\n";
      return 2;
    }
  }
  if (parser.isSet(f.ground)) {
    options.ground = findDataFile(parser.value(f.ground));
    if (!options.connectTo.isEmpty()) {
      std::cerr << "<command line>: error: --ground changes the built-in stand-in; it does not go with --connect\n";
      return 2;
    }
  }
  options.ghost = !parser.isSet(f.noGhost);
  options.calibrate = !parser.isSet(f.noCalibration);
  if (parser.isSet(f.quitAfter) && !(start.quitSeconds = numberOption(parser, f.quitAfter, 0.1, 1e6))) return 2;
  return std::nullopt;
}

// After `seconds`, prints the frame rate and the ghost's figures (measured
// after a warm-up: start, first telemetry, first layout), saves the
// screenshot when one is asked for, and closes the window.
void measureThenQuit(sp::MainWindow& window, double seconds, const QString& screenshot) {
  const double warmUp = seconds > 6 ? 3.0 : 0.0;
  auto* measure = new QObject(&window);
  auto framesAtWarmUp = std::make_shared<int64_t>(0);
  auto anchorsAtWarmUp = std::make_shared<int64_t>(0);
  auto wallAtWarmUp = std::make_shared<QElapsedTimer>();
  QTimer::singleShot(static_cast<int>(warmUp * 1000), measure, [&window, framesAtWarmUp, anchorsAtWarmUp, wallAtWarmUp] {
    *framesAtWarmUp = window.sceneView()->framesDrawn();
    if (const sp::Ghost* ghost = window.session()->ghost()) *anchorsAtWarmUp = ghost->stats().anchors;
    wallAtWarmUp->start();
  });
  QTimer::singleShot(static_cast<int>(seconds * 1000), measure, [&window, screenshot, framesAtWarmUp, anchorsAtWarmUp, wallAtWarmUp] {
    const double wall = static_cast<double>(wallAtWarmUp->nsecsElapsed()) * 1e-9;
    const int64_t frames = window.sceneView()->framesDrawn() - *framesAtWarmUp;
    std::cout << "frames " << frames << " in " << wall << " s: " << static_cast<double>(frames) / wall
              << " fps; 3D view " << window.sceneView()->width() << "x" << window.sceneView()->height()
              << " in a " << window.width() << "x" << window.height() << " window; real-time factor "
              << window.realTimeFactor() << "; telemetry frames " << window.telemetryReceived() << ", wheel-force replots "
              << window.wheelForcePlot()->replots() << ", laser replots " << window.laserPlot()->replots();
    if (const sp::Ghost* ghost = window.session()->ghost()) {
      const sp::GhostView v = ghost->view();
      const sp::GhostStats g = ghost->stats();
      std::cout << "; ghost +" << v.span << " s, " << g.anchors << " re-anchorings ("
                << static_cast<double>(g.anchors - *anchorsAtWarmUp) / wall << " per s measured; last " << g.anchorMs << " ms), "
                << g.trails << " trails of " << v.trail.size() << " points (last " << g.trailMs << " ms), drawn "
                << window.sceneView()->drawnTrailPoints();
      if (!v.trail.empty())
        std::cout << " from " << v.trail.front().x << "," << v.trail.front().y << "," << v.trail.front().z << " to "
                  << v.trail.back().x << "," << v.trail.back().y << "," << v.trail.back().z;
    }
    std::cout << std::endl;
    if (!screenshot.isEmpty()) window.grab().save(screenshot);
    window.close();
  });
}

}  // namespace

int main(int argc, char** argv) {
  sp::setSceneSurfaceFormat();  // before the application exists

  // The command line is read before any window system is touched: --help,
  // --version and bad options work without a display (a GUI application
  // aborts when it cannot open one).
  std::optional<QCoreApplication> bare(std::in_place, argc, argv);
  QCoreApplication::setApplicationName(QStringLiteral("SimPartner"));
  QCoreApplication::setOrganizationName(QStringLiteral("SimPartner"));
  QCoreApplication::setApplicationVersion(QStringLiteral(SP_VERSION));

  QCommandLineParser parser;
  parser.setApplicationDescription(QStringLiteral(
      "The SimPartner operator console. By default it starts the stand-in robot (the twin) on loopback "
      "and connects to it; --connect reaches any robot that speaks the link protocol."));
  const QCommandLineOption helpOption = parser.addHelpOption();
  const QCommandLineOption versionOption = parser.addVersionOption();
  const ConsoleFlags flags;
  parser.addOptions(flags.all());
  // Each job's own (--monitor, --rules, --sequence, --replay, ...): the jobs
  // exist before the window, and take their values before it installs them.
  sp::ConsoleJobs jobs = sp::builtInJobs();
  sp::addJobOptions(parser, jobs);
  if (!parser.parse(QCoreApplication::arguments())) {
    std::cerr << "<command line>: error: " << parser.errorText().toStdString() << "\n";
    return 2;
  }
  if (parser.isSet(helpOption)) {
    std::cout << parser.helpText().toStdString();
    return 0;
  }
  if (parser.isSet(versionOption)) {
    std::cout << "SimPartner " << SP_VERSION << "\n";
    return 0;
  }
  Start start;
  if (const std::optional<int> exit = readOptions(parser, flags, jobs, start)) return *exit;

  bare.reset();
  QApplication app(argc, argv);
  QApplication::setApplicationName(QStringLiteral("SimPartner"));
  QApplication::setOrganizationName(QStringLiteral("SimPartner"));
  QApplication::setApplicationVersion(QStringLiteral(SP_VERSION));
  QApplication::setWindowIcon(sp::appIcon());
  QGuiApplication::setDesktopFileName(QStringLiteral("simpartner"));  // matches the installed .desktop entry

  // Said where it was asked for: on the command line's stderr, as every
  // SimPartner tool does (a dialog would hang a scripted start), and in a
  // dialog when the desktop entry started us.
  const auto failed = [&](const QString& error) {
    jobs.clear();  // before the application they were made for
    std::cerr << error.toStdString() << "\n";
    if (parser.isSet(flags.errorDialog))
      QMessageBox::critical(nullptr, QObject::tr("SimPartner cannot start"), error);
    return 1;
  };
  if (!start.startError.isEmpty()) return failed(start.startError);
  sp::MainWindow window(start.options, std::move(jobs));
  if (const QString error = window.start(); !error.isEmpty()) return failed(error);
  window.show();
  if (!window.logPath().isEmpty()) std::cout << "logging to " << window.logPath().toStdString() << std::endl;
  if (parser.isSet(flags.quitAfter) || parser.isSet(flags.screenshot))
    measureThenQuit(window, start.quitSeconds.value_or(5.0), parser.value(flags.screenshot));
  return app.exec();
}
