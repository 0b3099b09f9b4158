#pragma once
// Draws an sp::PlotSpec (app/plot.h) with Qt Charts into a PNG file, off
// screen: no window is shown and no OpenGL is used, so it works headless with
// QT_QPA_PLATFORM=offscreen as well as under X11/xvfb-run.

#include <cstddef>
#include <cstdint>
#include <string>

#include "app/plot.h"

namespace sp {

/// Renders `plot` to a PNG of plot.width x plot.height pixels at `path`
/// (replaced atomically; the directory must exist): white background,
/// antialiased, title, axis titles, legend at the bottom (only if a series has
/// a name). Series i is drawn in plotSeriesColor(i). Non-finite points are
/// skipped (a line joins the points either side).
///
/// Returns false and sets `error` to one line naming the plot title and the
/// problem, e.g.
///   plot 'Wheel forces': series 'front_left': 3 x values but 2 y values
/// when: there are no series, a series has no points, x and y of different
/// lengths or no finite point, an axis range (given or fitted) is not finite,
/// has min >= max or a span that overflows, the size is outside 1..16384, the
/// file cannot be written (the reason from the OS follows), the application
/// object is unusable (see below) or the thread is wrong. Nothing is written
/// then. `error` is left alone on success.
///
/// Application object: Qt Charts needs a QApplication. If none exists, one is
/// created on the first call and kept until the process exits (it is never
/// destroyed, so nothing runs at exit; do not create another afterwards). If
/// then neither DISPLAY nor WAYLAND_DISPLAY is set and QT_QPA_PLATFORM is
/// unset, QT_QPA_PLATFORM is set to "offscreen" first, so a headless CI run
/// needs no X server. A caller that wants its own application creates a
/// QApplication (not a QCoreApplication, which is an error here) before the
/// first call, on any platform plugin.
///
/// Thread: GUI thread only (the thread of the QApplication, or the thread
/// that makes the first call when this function creates it); a call from any
/// other thread returns false.
bool renderPlotPng(const PlotSpec& plot, const std::string& path, std::string& error);

/// The colour of series `index` as 0xRRGGBB; the palette (Okabe-Ito, safe for
/// colour-blind readers) repeats after 8 series. Any thread.
std::uint32_t plotSeriesColor(std::size_t index);

}  // namespace sp
