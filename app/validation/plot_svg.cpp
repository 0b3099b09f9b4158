#include "app/validation/plot_svg.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <utility>
#include <vector>

namespace sp {
namespace {

constexpr int kMaxSide = 16384;

/// A finite interval, grown from points.
struct Extent {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  void add(double v) {
    min = std::min(min, v);
    max = std::max(max, v);
  }
  /// Widened by 5 % of its span on each side; a single value gets +-5 % of
  /// its magnitude (or +-1 at zero). Stays finite.
  std::pair<double, double> withMargin() const {
    constexpr double kMax = std::numeric_limits<double>::max();
    const double pad = max > min ? 0.05 * max - 0.05 * min : (min != 0 ? 0.05 * std::abs(min) : 1.0);
    return {std::max(min - pad, -kMax), std::min(max + pad, kMax)};
  }
};

std::string prefix(const PlotSpec& plot) { return "plot '" + plot.title + "': "; }

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

std::string rangeProblem(const char* axis, const std::pair<double, double>& r) {
  const std::string text = "(" + format("%g", r.first) + ", " + format("%g", r.second) + ")";
  if (!std::isfinite(r.first) || !std::isfinite(r.second) || !(r.first < r.second))
    return std::string(axis) + " range " + text + " must be finite with min < max";
  if (!std::isfinite(r.second - r.first)) return std::string(axis) + " range " + text + " is wider than a double can hold";
  return {};
}

/// The 1, 2 or 5 times a power of ten nearest above `raw` (> 0).
double niceStep(double raw) {
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw) return m * decade;
  return 10 * decade;
}

/// Tick values at multiples of a nice step inside [lo, hi], about one per
/// `pixelsPerTick` of `lengthPx`.
std::vector<double> ticks(std::pair<double, double> range, double lengthPx, double pixelsPerTick) {
  const double wanted = std::max(2.0, lengthPx / pixelsPerTick);
  const double step = niceStep((range.second - range.first) / wanted);
  std::vector<double> out;
  for (double k = std::ceil(range.first / step); k * step <= range.second + 1e-9 * step && out.size() < 100; ++k)
    out.push_back(std::abs(k * step) < 1e-12 * step ? 0.0 : k * step);
  return out;
}

std::string escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string colour(std::size_t series) {
  char text[16];
  std::snprintf(text, sizeof text, "#%06x", static_cast<unsigned>(plotSeriesColor(series)));
  return text;
}

std::string px(double v) { return format("%.2f", v); }

// Every series has points, as many x as y, some finite: "" or the problem.
// The finite points grow the extents.
std::string seriesProblem(const PlotSpec& plot, Extent& xExtent, Extent& yExtent) {
  for (const PlotSeries& s : plot.series) {
    const std::string where = prefix(plot) + "series '" + s.name + "': ";
    if (s.x.empty() && s.y.empty()) return where + "has no points";
    if (s.x.size() != s.y.size())
      return where + std::to_string(s.x.size()) + " x values but " + std::to_string(s.y.size()) + " y values";
    size_t finite = 0;
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      xExtent.add(s.x[k]);
      yExtent.add(s.y[k]);
      ++finite;
    }
    if (finite == 0) return where + "no finite point (all " + std::to_string(s.x.size()) + " skipped)";
  }
  return {};
}

struct LegendEntry {
  size_t series;
  double x;
  int row;
};

// The plot area and its axes' ranges, in user units (= px).
struct Area {
  double left, top, pw, ph;
  std::pair<double, double> xRange, yRange;
  double sx(double x) const { return left + (x - xRange.first) / (xRange.second - xRange.first) * pw; }
  double sy(double y) const { return top + ph - (y - yRange.first) / (yRange.second - yRange.first) * ph; }
};

// Legend entries (named series only) flow into rows from `left`; widths
// are estimated at about 7.5 units per character at font size 13.
std::vector<LegendEntry> layoutLegend(const PlotSpec& plot, double left, double right, int& rows) {
  std::vector<LegendEntry> legend;
  rows = 0;
  double x = left;
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const std::string& name = plot.series[i].name;
    if (name.empty()) continue;
    const double width = 19 + 7.5 * static_cast<double>(name.size()) + 22;
    if (rows == 0 || (x + width > plot.width - right && x > left)) {
      ++rows;
      x = left;
    }
    legend.push_back({i, x, rows - 1});
    x += width;
  }
  return legend;
}

// The grid, the frame, the tick labels and the axis titles.
void drawAxes(const PlotSpec& plot, const Area& a, std::string& svg) {
  svg += "<g stroke=\"#dddddd\" stroke-width=\"1\">\n";
  const std::vector<double> xTicks = ticks(a.xRange, a.pw, 100), yTicks = ticks(a.yRange, a.ph, 60);
  for (double x : xTicks)
    svg += "<line x1=\"" + px(a.sx(x)) + "\" y1=\"" + px(a.top) + "\" x2=\"" + px(a.sx(x)) + "\" y2=\"" + px(a.top + a.ph) + "\"/>\n";
  for (double y : yTicks)
    svg += "<line x1=\"" + px(a.left) + "\" y1=\"" + px(a.sy(y)) + "\" x2=\"" + px(a.left + a.pw) + "\" y2=\"" + px(a.sy(y)) + "\"/>\n";
  svg += "</g>\n<rect x=\"" + px(a.left) + "\" y=\"" + px(a.top) + "\" width=\"" + px(a.pw) + "\" height=\"" + px(a.ph) +
         "\" fill=\"none\" stroke=\"#555555\"/>\n";
  for (double x : xTicks)
    svg += "<text x=\"" + px(a.sx(x)) + "\" y=\"" + px(a.top + a.ph + 18) + "\" text-anchor=\"middle\">" +
           format("%.4g", x) + "</text>\n";
  for (double y : yTicks)
    svg += "<text x=\"" + px(a.left - 6) + "\" y=\"" + px(a.sy(y) + 4) + "\" text-anchor=\"end\">" + format("%.4g", y) +
           "</text>\n";
  if (!plot.xLabel.empty())
    svg += "<text x=\"" + px(a.left + a.pw / 2) + "\" y=\"" + px(a.top + a.ph + 40) + "\" text-anchor=\"middle\">" +
           escape(plot.xLabel) + "</text>\n";
  if (!plot.yLabel.empty())
    svg += "<text transform=\"translate(18 " + px(a.top + a.ph / 2) + ") rotate(-90)\" text-anchor=\"middle\">" +
           escape(plot.yLabel) + "</text>\n";
}

// The series, clipped to the plot area: points as dots, lines as polylines.
void drawSeries(const PlotSpec& plot, const Area& a, std::string& svg) {
  svg += "<g clip-path=\"url(#area)\">\n";
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const std::string c = colour(i);
    if (s.style == PlotSeries::Style::Points) {
      svg += "<g fill=\"" + c + "\" stroke=\"#333333\" stroke-width=\"0.5\">\n";
      for (size_t k = 0; k < s.x.size(); ++k)
        if (std::isfinite(s.x[k]) && std::isfinite(s.y[k]))
          svg += "<circle cx=\"" + px(a.sx(s.x[k])) + "\" cy=\"" + px(a.sy(s.y[k])) + "\" r=\"3.5\"/>\n";
      svg += "</g>\n";
    } else {
      svg += "<polyline fill=\"none\" stroke=\"" + c +
             "\" stroke-width=\"2\" stroke-linejoin=\"round\" stroke-linecap=\"round\" points=\"";
      for (size_t k = 0; k < s.x.size(); ++k)
        if (std::isfinite(s.x[k]) && std::isfinite(s.y[k])) svg += px(a.sx(s.x[k])) + "," + px(a.sy(s.y[k])) + " ";
      svg += "\"/>\n";
    }
  }
  svg += "</g>\n";
}

}  // namespace

std::optional<std::string> renderPlotSvg(const PlotSpec& plot, std::string& error) {
  if (plot.series.empty()) {
    error = prefix(plot) + "has no series";
    return std::nullopt;
  }
  if (plot.width < 1 || plot.width > kMaxSide || plot.height < 1 || plot.height > kMaxSide) {
    error = prefix(plot) + "size " + std::to_string(plot.width) + "x" + std::to_string(plot.height) +
            " is outside 1.." + std::to_string(kMaxSide) + " pixels";
    return std::nullopt;
  }
  Extent xExtent, yExtent;
  if (std::string p = seriesProblem(plot, xExtent, yExtent); !p.empty()) {
    error = p;
    return std::nullopt;
  }
  const std::pair<double, double> xRange = plot.xRange.value_or(xExtent.withMargin());
  const std::pair<double, double> yRange = plot.yRange.value_or(yExtent.withMargin());
  for (const auto& [axis, range] : {std::pair{"x", xRange}, std::pair{"y", yRange}}) {
    if (std::string p = rangeProblem(axis, range); !p.empty()) {
      error = prefix(plot) + p;
      return std::nullopt;
    }
  }

  // Layout: title on top, y labels left, x labels and the legend below the plot area.
  const double w = plot.width, h = plot.height;
  const double left = 78, right = 18, top = plot.title.empty() ? 16 : 40;
  int legendRows = 0;
  const std::vector<LegendEntry> legend = layoutLegend(plot, left, right, legendRows);
  const double bottom = 52 + 22 * legendRows + (legendRows > 0 ? 4 : 0);
  const Area area{left, top, std::max(1.0, w - left - right), std::max(1.0, h - top - bottom), xRange, yRange};
  const double pw = area.pw, ph = area.ph;

  std::string svg;
  svg += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(plot.width) + "\" height=\"" +
         std::to_string(plot.height) + "\" viewBox=\"0 0 " + std::to_string(plot.width) + " " +
         std::to_string(plot.height) + "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"13\">\n";
  svg += "<title>" + escape(plot.title) + "</title>\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg += "<defs><clipPath id=\"area\"><rect x=\"" + px(left) + "\" y=\"" + px(top) + "\" width=\"" + px(pw) +
         "\" height=\"" + px(ph) + "\"/></clipPath></defs>\n";
  if (!plot.title.empty())
    svg += "<text x=\"" + px(w / 2) + "\" y=\"26\" text-anchor=\"middle\" font-size=\"17\" font-weight=\"bold\">" +
           escape(plot.title) + "</text>\n";
  drawAxes(plot, area, svg);
  drawSeries(plot, area, svg);
  // Legend: named series only, in rows under the axis title.
  for (const LegendEntry& e : legend) {
    const double y = top + ph + 66 + 22 * e.row;
    svg += "<rect x=\"" + px(e.x) + "\" y=\"" + px(y - 10) + "\" width=\"14\" height=\"10\" fill=\"" +
           colour(e.series) + "\"/><text x=\"" + px(e.x + 19) + "\" y=\"" + px(y) + "\">" +
           escape(plot.series[e.series].name) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

bool writePlotSvg(const PlotSpec& plot, const std::string& path, std::string& error) {
  std::optional<std::string> svg = renderPlotSvg(plot, error);
  if (!svg) return false;
  const std::string temp = path + ".part";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (out) out << *svg;
    if (out) out.flush();
    if (!out) {
      const int e = errno;
      std::error_code ec;
      std::filesystem::remove(temp, ec);
      error = prefix(plot) + "cannot write '" + path + "': " + std::strerror(e);
      return false;
    }
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    error = prefix(plot) + "cannot write '" + path + "': " + ec.message();
    return false;
  }
  return true;
}

}  // namespace sp
