// Benchmark of terrain editing (issue 16): prints figures, asserts nothing.
// Goal: a stroke on a 512 x 512 grid at 60 Hz keeps the view at its frame
// rate and the twin at real time. Needs a display for part 2:
//
//   xvfb-run -a -s "-screen 0 1280x1024x24" build/bench/bench_terrain [--quick]
//
// The world: WorkPartner at rest on a 512 x 512 heightfield, 51.1 m square
// (0.1 m samples, gentle waves), written to /tmp.
//
// 1. The twin: the step loop of a World on that world, with no edits and
//    with a stroke of raise dabs (radius 1 m and 3 m) at 60 Hz, i.e. one
//    patch every 16.7 steps of 1 ms, circling under the robot; rounds
//    alternate so machine load hits both alike. Figures: us per step
//    (medians over rounds), the real-time factor, and what a dab costs to
//    compute (brushDab) and to apply (World::submit, at the next step).
// 2. The view: a SceneView drawing the world at 1280 x 800 for 3 s as it is,
//    then 3 s with a 60 Hz stroke applied to it (SceneView::applyTerrainPatch:
//    the patch's vertices updated in place); frames per second of each,
//    and the median time of one applyTerrainPatch.

#include <QApplication>
#include <QElapsedTimer>
#include <QTemporaryDir>
#include <QTimer>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sim/model_loader.h"
#include "sim/terrain_brush.h"
#include "sim/world.h"
#include "ui/scene_view.h"

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// The 512 x 512 world in `dir`; its path.
std::string writeWorld(const QString& dir) {
  const std::string csv = dir.toStdString() + "/big.csv", world = dir.toStdString() + "/big.world.xml";
  std::ofstream grid(csv);
  for (int j = 0; j < 512; ++j) {
    for (int i = 0; i < 512; ++i) grid << (i ? "," : "") << 0.05 * std::sin(i * 0.05) * std::cos(j * 0.07);
    grid << "\n";
  }
  std::ofstream w(world);
  w << "<world name=\"big\" version=\"1\">\n  <material name=\"ground\"/>\n  <material name=\"rubber\"/>\n"
       "  <contact default=\"true\" mu=\"0.8\"/>\n"
       "  <terrain type=\"heightfield\" file=\"big.csv\" width=\"51.1\" depth=\"51.1\" material=\"ground\"/>\n"
       "  <robot name=\"workpartner\" file=\"" SP_SOURCE_DIR "/robots/workpartner.xml\" xyz=\"0 0 0.1\"/>\n</world>\n";
  return world;
}

// Dab k of a stroke circling 1.5 m around the robot, 6 dabs a turn per second.
sp::Vec2 strokePoint(int k) { return {1.5 * std::cos(k * 0.1), 1.5 * std::sin(k * 0.1)}; }

void benchTwin(const sp::WorldModel& model, bool quick) {
  sp::Diagnostics diag;
  const int rounds = quick ? 3 : 7, steps = quick ? 1000 : 3000;
  std::printf("1. The twin: WorkPartner on the 512 x 512 heightfield, %d rounds x %d steps of 1 ms\n", rounds, steps);
  for (double radius : {1.0, 3.0}) {
    std::vector<double> plain, edited, compute, submitStep;
    const sp::Brush brush{sp::BrushKind::Raise, radius, 0.002, 0, 1};
    int dabSamples = 0;
    for (int r = 0; r < rounds; ++r)
      for (bool edits : {false, true}) {
        std::unique_ptr<sp::World> world = sp::World::create(model, {}, diag);
        for (int s = 0; s < 300; ++s) world->step();  // settled
        int k = 0;
        double nextDab = 0;
        const auto t0 = Clock::now();
        for (int s = 0; s < steps; ++s) {
          if (edits && s >= nextDab) {
            const auto a = Clock::now();
            const auto patch = sp::brushDab(*world->terrainGrid(), strokePoint(k++), brush);
            const auto b = Clock::now();
            compute.push_back(seconds(a, b) * 1e6);
            dabSamples = static_cast<int>(patch->heights.size());
            world->submit(*patch);
            world->step();  // applies it
            submitStep.push_back(seconds(b, Clock::now()) * 1e6);
            nextDab += 1000.0 / 60;
            continue;
          }
          world->step();
        }
        (edits ? edited : plain).push_back(seconds(t0, Clock::now()) / steps * 1e6);
      }
    const double a = median(plain), b = median(edited);
    std::printf("  radius %.0f m (%d samples a dab): %.1f us/step without edits, %.1f with a 60 Hz stroke (%+.1f %%); "
                "real time x%.1f; a dab costs %.0f us to compute, its step %.0f us\n",
                radius, dabSamples, a, b, (b / a - 1) * 100, 1000.0 / b, median(compute), median(submitStep));
  }
}

void benchView(QApplication& app, const sp::WorldModel& model, bool quick) {
  sp::SceneView view;
  view.resize(1280, 800);
  view.show();
  view.setWorld(model);
  view.setFollow(false);
  const double period = quick ? 2.0 : 3.0;
  sp::HeightGrid grid = model.terrain.grid;
  std::printf("2. The view at 1280 x 800 (software GL under Xvfb), %.0f s each\n", period);
  for (double radius : {0.0, 1.0, 3.0}) {
    std::vector<double> apply;
    int k = 0;
    QTimer dabs;
    dabs.setInterval(16);
    QElapsedTimer stroke;
    // 60 dabs per second of wall time whatever the frame rate: a tick
    // applies every dab due since the last (a frame may take longer than 16 ms).
    QObject::connect(&dabs, &QTimer::timeout, [&] {
      while (k < stroke.elapsed() * 60 / 1000) {
        const auto patch = sp::brushDab(grid, strokePoint(k++), sp::Brush{sp::BrushKind::Raise, radius, 0.002, 0, 1});
        sp::applyPatch(grid, *patch);
        QElapsedTimer t;
        t.start();
        view.applyTerrainPatch(*patch);
        apply.push_back(static_cast<double>(t.nsecsElapsed()) * 1e-6);
      }
    });
    // Settle a second, then count the frames of the period.
    QElapsedTimer settle;
    settle.start();
    while (settle.elapsed() < 1000) app.processEvents(QEventLoop::AllEvents, 20);
    stroke.start();
    if (radius > 0) dabs.start();
    QElapsedTimer wall;
    wall.start();
    double fpsSum = 0;
    int samples = 0;
    while (static_cast<double>(wall.elapsed()) < period * 1000) {
      app.processEvents(QEventLoop::AllEvents, 20);
      if (wall.elapsed() > 1100 * (samples + 1)) {
        fpsSum += view.framesPerSecond();
        ++samples;
      }
    }
    dabs.stop();
    if (radius == 0)
      std::printf("  no edits: %.1f frames/s\n", samples ? fpsSum / samples : view.framesPerSecond());
    else
      std::printf("  a 60 Hz stroke of radius %.0f m: %.1f frames/s, %zu patches applied, applyTerrainPatch median %.2f ms\n",
                  radius, samples ? fpsSum / samples : view.framesPerSecond(), apply.size(), median(apply));
  }
}

}  // namespace

int main(int argc, char** argv) {
  sp::setSceneSurfaceFormat();  // before the application
  QApplication app(argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const bool quick = argc > 1 && std::string(argv[1]) == "--quick";
  QTemporaryDir dir;
  sp::Diagnostics diag;
  const std::optional<sp::WorldModel> model = sp::loadWorld(writeWorld(dir.path()), diag);
  if (!model) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    return 1;
  }
  benchTwin(*model, quick);
  benchView(app, *model, quick);
  return 0;
}
