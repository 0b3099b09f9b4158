// Benchmark of replay in the console's UI path (issue 15): prints figures,
// asserts nothing. Needs a display (xvfb-run) and a log, e.g. the one-hour
// 1 kHz log `bench_log --hour --keep` leaves in /tmp:
//
//   xvfb-run -a -s "-screen 0 1280x1024x24" build/bench/bench_replay LOG
//
// 1. Opening: the window opens LOG on the Replay dock's worker (as File ▸
//    Open session log does) while a 5 ms timer on the GUI thread records
//    the longest gap between its ticks: how long the window stops
//    answering. Baseline in the same process: the blocking open
//    (ReplayPanel::open), which is how long it would freeze without the worker.
// 2. Seeking (goal <= 50 ms): ReplayPanel::seek to 100 random times (fixed
//    seed) as dragging the timeline does, each followed by a repaint of the
//    3D view (the robot drawn at the new pose) and the event queue run:
//    the whole of what a seek costs the operator. Warm (the file in the page
//    cache) and cold (its cached pages dropped before each seek). Baseline
//    in the same process: the repaint and event run without a seek.

#include <fcntl.h>
#include <unistd.h>

#include <QApplication>
#include <QElapsedTimer>
#include <QTemporaryDir>
#include <QTimer>

#include <algorithm>
#include <cstdio>
#include <random>
#include <vector>

#include "app/log/log_player.h"
#include "ui/jobs/jobs.h"
#include "ui/main_window.h"
#include "ui/jobs/replay/replay_job.h"
#include "ui/jobs/replay/replay_panel.h"
#include "ui/scene_view.h"

namespace {

void dropCache(const QString& path) {
  const int fd = open(path.toLocal8Bit().constData(), O_RDONLY);
  if (fd < 0) return;
  posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  close(fd);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

double ms(const QElapsedTimer& t) { return static_cast<double>(t.nsecsElapsed()) * 1e-6; }

}  // namespace

int main(int argc, char** argv) {
  sp::setSceneSurfaceFormat();  // before the application
  QApplication app(argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // each figure as it comes
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench_replay LOG   (under xvfb-run; LOG e.g. from bench_log --hour --keep)\n");
    return 2;
  }
  const QString log = QString::fromLocal8Bit(argv[1]);
  {
    // Replayable at all? (Else the window would stop at its error dialog.)
    std::string error;
    if (!sp::LogPlayer::open(argv[1], error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
  }
  QTemporaryDir dir;
  sp::ConsoleOptions options;
  options.world = QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml");
  options.log = false;
  options.logDir = dir.path();
  sp::MainWindow window(options, sp::builtInJobs());
  if (const QString e = window.start(); !e.isEmpty()) {
    std::fprintf(stderr, "%s\n", qPrintable(e));
    return 1;
  }
  window.resize(1280, 800);
  window.show();
  sp::ReplayJob* replayJob = window.job<sp::ReplayJob>();
  sp::ReplayPanel* replay = replayJob->panel();

  // 1. Opening.
  double longestGap = 0;
  int ticks = 0;
  QElapsedTimer sinceTick;
  QTimer ticker;
  ticker.setInterval(5);
  QObject::connect(&ticker, &QTimer::timeout, [&] {
    longestGap = std::max(longestGap, ms(sinceTick));
    sinceTick.start();
    ++ticks;
  });
  dropCache(log);
  QElapsedTimer opening;
  opening.start();
  sinceTick.start();
  ticker.start();
  replayJob->openLogInBackground(log);
  while (replay->busy()) app.processEvents(QEventLoop::AllEvents, 50);
  ticker.stop();
  const double openMs = ms(opening);
  if (!replay->isOpen()) {
    std::fprintf(stderr, "%s: did not open\n", argv[1]);
    return 1;
  }
  std::printf("Replay of %s: %.0f s of log, %zu events\n", argv[1], replay->player()->endTime() - replay->player()->startTime(),
              replay->player()->events().size());
  std::printf("  open on the worker (cold): %.0f ms; the window answered every %.1f ms at worst (%d ticks of 5 ms)\n",
              openMs, longestGap, ticks);
  replay->close();
  dropCache(log);
  QElapsedTimer blocking;
  blocking.start();
  const QString error = replay->open(log);
  std::printf("  baseline, the blocking open (cold): %.0f ms frozen%s\n", ms(blocking), qPrintable(error));

  // 2. Seeking.
  const double t0 = replay->player()->startTime(), t1 = replay->player()->endTime();
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> at(t0, t1);
  std::vector<double> times(100);
  for (double& t : times) t = at(rng);
  // Baseline: the same repaint and event run without a seek (the frame's
  // rendering: software GL under Xvfb, sharing 2 cores with the stand-in).
  {
    std::vector<double> frame;
    for (int i = 0; i < 100; ++i) {
      QElapsedTimer timer;
      timer.start();
      window.sceneView()->repaint();
      app.processEvents();
      frame.push_back(ms(timer));
    }
    std::printf("  baseline, repaint and events without a seek: median %.2f ms, worst %.2f ms\n", median(frame),
                *std::max_element(frame.begin(), frame.end()));
  }
  for (bool cold : {false, true}) {
    std::vector<double> seek, total;
    for (double t : times) {
      if (cold) dropCache(log);
      QElapsedTimer timer;
      timer.start();
      replay->seek(t);
      seek.push_back(ms(timer));
      window.sceneView()->repaint();
      app.processEvents();
      total.push_back(ms(timer));
    }
    std::printf("  %s seek, 100 random t: ReplayPanel::seek median %.2f ms, worst %.2f ms; with the 3D view "
                "repainted and events run median %.2f ms, worst %.2f ms (goal <= 50 ms)\n",
                cold ? "cold" : "warm", median(seek), *std::max_element(seek.begin(), seek.end()), median(total),
                *std::max_element(total.begin(), total.end()));
  }
  return 0;
}
