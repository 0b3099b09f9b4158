// A tiny program for tst_plot_renderer: renders one plot and exits, so the
// test can see that a process which renders ends without crashing at exit.
//   plot_render_once auto <png>  renderPlotPng creates the QApplication
//   plot_render_once own <png>   main owns a QApplication, destroyed on return
// Prints the platform plugin's name; exit code 0 on success, 1 on a render
// error (message on stderr), 2 on bad arguments.

#include <QApplication>
#include <QGuiApplication>

#include <cstdio>
#include <memory>
#include <string>

#include "ui/plot_renderer.h"

int main(int argc, char** argv) {
  if (argc != 3 || (std::string(argv[1]) != "auto" && std::string(argv[1]) != "own")) {
    std::fprintf(stderr, "usage: plot_render_once auto|own <png>\n");
    return 2;
  }
  std::unique_ptr<QApplication> app;
  if (std::string(argv[1]) == "own") app = std::make_unique<QApplication>(argc, argv);

  sp::PlotSpec plot;
  plot.title = "Exit check";
  plot.xLabel = "time [s]";
  plot.yLabel = "force [N]";
  plot.width = 320;
  plot.height = 200;
  plot.series.push_back({"rising", {0, 1, 2, 3}, {0, 1, 4, 9}});
  plot.series.push_back({"dots", {0, 1, 2, 3}, {9, 4, 1, 0}, sp::PlotSeries::Style::Points});
  std::string error;
  if (!sp::renderPlotPng(plot, argv[2], error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  std::printf("%s\n", qPrintable(QGuiApplication::platformName()));
  return 0;
}
