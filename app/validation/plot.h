#pragma once
// A plot described as plain data (no Qt), for the validation report of
// `simpartner-sim validate`: the validator fills a PlotSpec, app/plot_svg
// draws it and toCsv() writes the same numbers for pandas.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <system_error>
#include <unordered_set>
#include <utility>
#include <vector>

namespace sp {

/// One curve: x[i] pairs with y[i]. Non-finite points are skipped when drawn.
struct PlotSeries {
  std::string name;  ///< legend text and CSV column name; may be empty
  std::vector<double> x, y;
  enum class Style { Line, Points } style = Style::Line;
};

/// A 2-D plot. Plain data; copy freely, use from any thread.
struct PlotSpec {
  std::string title, xLabel, yLabel;
  std::vector<PlotSeries> series;
  int width = 960, height = 540;  ///< image size [px]
  /// Axis ranges (min, max). Default: fit the finite data with a margin.
  std::optional<std::pair<double, double>> xRange, yRange;
};

/// The colour of series `index` as 0xRRGGBB, shared by the report's plots
/// and the console's live plots: Okabe-Ito without black (it would look like
/// the axes), safe for colour-blind readers; it repeats after 8 series.
inline std::uint32_t plotSeriesColor(std::size_t index) {
  static constexpr std::array<std::uint32_t, 8> kPalette = {0x0072B2, 0xD55E00, 0x009E73, 0xE69F00,
                                                            0xCC79A7, 0x56B4E9, 0xF0E442, 0x666666};
  return kPalette[index % kPalette.size()];
}

/// `text` as a CSV column name: lower case, every run of characters outside
/// [a-z0-9] becomes one '_', no '_' at either end ("Time [s]" -> "time_s",
/// "Front left (N)" -> "front_left_n"). Returns `fallback` if nothing is left.
inline std::string plotColumnName(const std::string& text, const std::string& fallback) {
  std::string out;
  bool pendingSeparator = false;
  for (const char c : text) {
    const char lower = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    if ((lower >= 'a' && lower <= 'z') || (lower >= '0' && lower <= '9')) {
      if (pendingSeparator && !out.empty()) out += '_';
      pendingSeparator = false;
      out += lower;
    } else {
      pendingSeparator = true;
    }
  }
  return out.empty() ? fallback : out;
}

/// The plot's numbers as one CSV table, readable by pandas.read_csv.
///
/// Two columns per series, in order: x named after xLabel, y after the series
/// name (see plotColumnName; fallbacks "x" and "series<i>", i from 1). A name
/// already taken gets "_2", "_3", ... so every column name is unique:
///   time_s,front_left_n,time_s_2,front_right_n
/// There is one row per index up to the longest column; a column that is
/// shorter has empty cells there (NaN in pandas). Values are written in the
/// shortest form that reads back to the same double; non-finite ones as
/// "nan", "inf", "-inf". Lines end with '\n'. A plot without series gives "".
inline std::string toCsv(const PlotSpec& plot) {
  if (plot.series.empty()) return {};

  // Header, with unique names.
  std::unordered_set<std::string> taken;
  const auto unique = [&taken](const std::string& base) {
    std::string name = base;
    for (int suffix = 2; taken.count(name) != 0; ++suffix) name = base + '_' + std::to_string(suffix);
    taken.insert(name);
    return name;
  };
  std::vector<const std::vector<double>*> columns;
  std::string csv;
  std::size_t rows = 0;
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    if (i > 0) csv += ',';
    csv += unique(plotColumnName(plot.xLabel, "x"));
    csv += ',';
    csv += unique(plotColumnName(s.name, "series" + std::to_string(i + 1)));
    columns.push_back(&s.x);
    columns.push_back(&s.y);
    rows = std::max({rows, s.x.size(), s.y.size()});
  }
  csv += '\n';

  // Rows.
  char buffer[64];
  for (std::size_t row = 0; row < rows; ++row) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c > 0) csv += ',';
      const std::vector<double>& column = *columns[c];
      if (row >= column.size()) continue;
      if (std::isnan(column[row])) {  // to_chars would write "-nan" for some
        csv += "nan";
        continue;
      }
      const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, column[row]);
      if (ec == std::errc()) csv.append(buffer, end);
    }
    csv += '\n';
  }
  return csv;
}

}  // namespace sp
