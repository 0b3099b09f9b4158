#pragma once
// Draws an sp::PlotSpec (app/validation/plot.h) as an SVG file: plain text, no Qt, no
// fonts to load, so `simpartner-sim validate` writes its report's plots
// without linking any GUI library, and any browser or Markdown viewer shows
// them.

#include <optional>
#include <string>

#include "app/validation/plot.h"

namespace sp {

/// The SVG text of `plot`: plot.width x plot.height user units, white
/// background, title, axes with ticks at round 1-2-5 steps and a light grid,
/// axis titles, one polyline (or circles for Style::Points) per series in
/// plotSeriesColor(i), clipped to the plot area, and a legend at the bottom
/// when a series has a name. Non-finite points are skipped (a line joins the
/// points either side).
///
/// Returns nullopt and sets `error` to one line naming the plot and the
/// problem, e.g.
///   plot 'Wheel forces': series 'front_left': 3 x values but 2 y values
/// when there are no series, a series has no points, x and y of different
/// lengths or no finite point, an axis range (given or fitted) is not
/// finite, has min >= max or a span that overflows, or the size is outside
/// 1..16384. Any thread.
std::optional<std::string> renderPlotSvg(const PlotSpec& plot, std::string& error);

/// renderPlotSvg() written to `path` through a temporary file renamed into
/// place, so a report never holds half a plot. On any error (those above,
/// or the file cannot be written: the OS's reason follows) returns false,
/// sets `error` and leaves no file. Any thread.
bool writePlotSvg(const PlotSpec& plot, const std::string& path, std::string& error);

}  // namespace sp
