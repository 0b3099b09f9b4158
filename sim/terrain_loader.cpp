#include "sim/terrain_loader.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "sim/text.h"

namespace sp {
namespace {

constexpr int kMinSamples = 2;     // per axis
constexpr int kMaxSamples = 4096;  // per axis
constexpr int kMaxErrors = 20;     // per file, then the loader gives up

// Collects the errors of one file. After kMaxErrors it records a single
// "too many errors" line and ignores the rest, so a badly broken file gives a
// readable report instead of thousands of lines; loops stop once full().
class Reporter {
 public:
  Reporter(std::string_view path, Diagnostics& diag) : path_(path), diag_(diag) {}

  void error(int line, std::string message) {
    if (full()) return;
    ++count_;
    diag_.error(path_, line, count_ > kMaxErrors ? "too many errors; giving up" : std::move(message));
  }
  bool failed() const { return count_ > 0; }
  bool full() const { return count_ > kMaxErrors; }

 private:
  std::string_view path_;
  Diagnostics& diag_;
  int count_ = 0;
};

// ---------------------------------------------------------------------------
// Text helpers

struct Line {
  std::string_view text;  // without the line terminator
  int number = 0;         // 1-based
};

std::vector<Line> splitLines(std::string_view content) {
  std::vector<Line> lines;
  int number = 0;
  size_t start = 0;
  while (start < content.size()) {
    size_t end = content.find('\n', start);
    if (end == std::string_view::npos) end = content.size();
    std::string_view text = content.substr(start, end - start);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    lines.push_back({text, ++number});
    start = end + 1;
  }
  return lines;
}

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Splits on commas and trims spaces around each field; "" gives one empty field.
std::vector<std::string_view> splitCommas(std::string_view s) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = s.find(',', start);
    fields.push_back(
        trim(s.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

// A finite decimal number, the whole token ("+1.5" accepted, "nan" and "inf" not).
std::optional<double> parseDouble(std::string_view s) {
  if (s.size() > 1 && s.front() == '+' && s[1] != '-') s.remove_prefix(1);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<long> parseInteger(std::string_view s) {
  if (s.size() > 1 && s.front() == '+' && s[1] != '-') s.remove_prefix(1);
  long value = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return value;
}

std::string quote(std::string_view s) { return "'" + std::string(s) + "'"; }

std::string toLower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

std::string rowColumn(long row, long column) {
  return "row " + std::to_string(row) + ", column " + std::to_string(column);
}

// Checks a sample count against [kMinSamples, kMaxSamples]; what names it.
bool checkCount(Reporter& r, int line, std::string_view what, long count) {
  if (count >= kMinSamples && count <= kMaxSamples) return true;
  r.error(line, std::string(what) + " must be between " + std::to_string(kMinSamples) + " and " +
                    std::to_string(kMaxSamples) + ", got " + std::to_string(count));
  return false;
}

// Builds the grid from values in file order (row-major, first row north),
// flipping rows into HeightGrid's +y order.
HeightGrid gridFromNorthFirst(int columns, int rows, double width, double depth,
                              const std::vector<double>& northFirst) {
  HeightGrid grid;
  grid.columns = columns;
  grid.rows = rows;
  grid.width = width;
  grid.depth = depth;
  grid.heights.resize(static_cast<size_t>(columns) * static_cast<size_t>(rows));
  for (int r = 0; r < rows; ++r)
    for (int i = 0; i < columns; ++i)
      grid.at(i, rows - 1 - r) = northFirst[static_cast<size_t>(r) * columns + i];
  return grid;
}

// ---------------------------------------------------------------------------
// ESRI ASCII grid

enum AscKey {
  kNcols,
  kNrows,
  kXllCorner,
  kXllCenter,
  kYllCorner,
  kYllCenter,
  kCellSize,
  kNodata,
  kAscKeyCount
};
constexpr std::array<std::string_view, kAscKeyCount> kAscKeyNames = {
    "ncols", "nrows", "xllcorner", "xllcenter", "yllcorner", "yllcenter", "cellsize", "nodata_value"};

std::optional<HeightGrid> loadAsc(const TerrainSource& source, std::string_view content, Reporter& r) {
  const std::vector<Line> lines = splitLines(content);

  // Header: "key value" lines until the first line that starts with a number.
  struct HeaderValue {
    std::string_view text;
    int line = 0;
  };
  std::array<HeaderValue, kAscKeyCount> header{};
  size_t dataStart = 0;
  for (; dataStart < lines.size(); ++dataStart) {
    const Line& line = lines[dataStart];
    const std::vector<std::string_view> tokens = splitWords(line.text);
    if (tokens.empty()) continue;
    const char first = tokens[0][0];
    if (!((first >= 'a' && first <= 'z') || (first >= 'A' && first <= 'Z'))) break;
    const std::string key = toLower(tokens[0]);
    const auto known = std::find(kAscKeyNames.begin(), kAscKeyNames.end(), key);
    if (known == kAscKeyNames.end()) {
      r.error(line.number, "unknown header key " + quote(tokens[0]));
      continue;
    }
    if (tokens.size() != 2) {
      r.error(line.number, "header line needs one value after " + quote(tokens[0]) + ", found " +
                               std::to_string(tokens.size() - 1));
      continue;
    }
    HeaderValue& slot = header[static_cast<size_t>(known - kAscKeyNames.begin())];
    if (slot.line != 0) {
      r.error(line.number, "duplicate header key " + quote(tokens[0]) + " (first on line " +
                               std::to_string(slot.line) + ")");
      continue;
    }
    slot = {tokens[1], line.number};
  }
  if (lines.empty()) {
    r.error(0, "terrain file is empty");
    return std::nullopt;
  }
  // Missing keys are reported where the data begins (or at the last line).
  const int dataLine = dataStart < lines.size() ? lines[dataStart].number : lines.back().number;

  const auto integerKey = [&](AscKey key) -> long {
    const HeaderValue& v = header[key];
    if (v.line == 0) {
      r.error(dataLine, "missing header key " + quote(kAscKeyNames[key]));
      return 0;
    }
    const std::optional<long> n = parseInteger(v.text);
    if (!n) {
      r.error(v.line, std::string(kAscKeyNames[key]) + " must be an integer, got " + quote(v.text));
      return 0;
    }
    return checkCount(r, v.line, kAscKeyNames[key], *n) ? *n : 0;
  };
  const auto numberKey = [&](AscKey key) -> std::optional<double> {
    const HeaderValue& v = header[key];
    if (v.line == 0) return std::nullopt;
    const std::optional<double> x = parseDouble(v.text);
    if (!x) r.error(v.line, std::string(kAscKeyNames[key]) + " must be a number, got " + quote(v.text));
    return x;
  };
  // Exactly one of a corner/center pair; the value itself is not needed
  // because the grid is centred on the terrain origin.
  const auto originKey = [&](AscKey corner, AscKey center) {
    const HeaderValue& a = header[corner];
    const HeaderValue& b = header[center];
    if (a.line == 0 && b.line == 0) {
      r.error(dataLine,
              "missing header key " + quote(kAscKeyNames[corner]) + " or " + quote(kAscKeyNames[center]));
    } else if (a.line != 0 && b.line != 0) {
      r.error(std::max(a.line, b.line),
              "both " + quote(kAscKeyNames[corner]) + " and " + quote(kAscKeyNames[center]) + " given");
    } else {
      numberKey(a.line != 0 ? corner : center);
    }
  };

  const long ncols = integerKey(kNcols);
  const long nrows = integerKey(kNrows);
  originKey(kXllCorner, kXllCenter);
  originKey(kYllCorner, kYllCenter);
  double cellSize = 0;
  if (header[kCellSize].line == 0) {
    r.error(dataLine, "missing header key 'cellsize'");
  } else if (const std::optional<double> c = numberKey(kCellSize)) {
    if (*c > 0)
      cellSize = *c;
    else
      r.error(header[kCellSize].line, "cellsize must be > 0, got " + quote(header[kCellSize].text));
  }
  const std::optional<double> nodata = numberKey(kNodata);
  // The data layout cannot be read without a valid header.
  if (r.failed()) return std::nullopt;

  // Count values per data line first: one row per line is checked row by row,
  // any other layout (rows wrapped over several lines) only by the total.
  struct DataLine {
    size_t index;  // into lines
    long count;
  };
  std::vector<DataLine> dataLines;
  long total = 0;
  for (size_t k = dataStart; k < lines.size(); ++k) {
    const long count = static_cast<long>(splitWords(lines[k].text).size());
    if (count == 0) continue;
    dataLines.push_back({k, count});
    total += count;
  }
  const long expected = ncols * nrows;
  const bool rowPerLine = static_cast<long>(dataLines.size()) == nrows;
  if (rowPerLine) {
    for (size_t k = 0; k < dataLines.size(); ++k)
      if (dataLines[k].count != ncols)
        r.error(lines[dataLines[k].index].number, "expected " + std::to_string(ncols) + " values in row " +
                                                      std::to_string(k + 1) + ", found " +
                                                      std::to_string(dataLines[k].count));
  } else if (total != expected) {
    // Too many: name the line of the first extra value; too few: the last line.
    int line = dataLine;
    long seen = 0;
    for (const DataLine& d : dataLines) {
      line = lines[d.index].number;
      seen += d.count;
      if (seen > expected) break;
    }
    r.error(line, "expected " + std::to_string(nrows) + " rows of " + std::to_string(ncols) + " values (" +
                      std::to_string(expected) + " in all), found " + std::to_string(total));
  }

  // Parse every value; name its row and column (1-based, as in the file).
  std::vector<double> values;
  values.reserve(static_cast<size_t>(std::min(total, expected)));
  long index = 0;  // running value index, for the wrapped layout
  for (size_t k = 0; k < dataLines.size() && !r.full(); ++k) {
    const Line& line = lines[dataLines[k].index];
    const std::vector<std::string_view> tokens = splitWords(line.text);
    for (size_t t = 0; t < tokens.size() && !r.full(); ++t, ++index) {
      const long row = rowPerLine ? static_cast<long>(k) + 1 : index / ncols + 1;
      const long column = rowPerLine ? static_cast<long>(t) + 1 : index % ncols + 1;
      const std::optional<double> v = parseDouble(tokens[t]);
      if (!v) {
        r.error(line.number, quote(tokens[t]) + " is not a finite number (" + rowColumn(row, column) + ")");
      } else if (nodata && *v == *nodata) {
        r.error(line.number, "NODATA value " + std::string(tokens[t]) + " in " + rowColumn(row, column));
      } else {
        values.push_back(*v);
      }
    }
  }
  if (r.failed()) return std::nullopt;

  const int columns = static_cast<int>(ncols);
  const int rows = static_cast<int>(nrows);
  const double width = source.width > 0 ? source.width : (columns - 1) * cellSize;
  const double depth = source.depth > 0 ? source.depth : (rows - 1) * cellSize;
  return gridFromNorthFirst(columns, rows, width, depth, values);
}

// ---------------------------------------------------------------------------
// PGM (P2 plain, P5 raw; 8 or 16 bit)

// Reads whitespace-separated tokens of a PGM header, skipping # comments and
// counting lines.
class PgmCursor {
 public:
  explicit PgmCursor(std::string_view data) : data_(data) {}

  // The next token, or empty at the end of the data.
  std::string_view token() {
    while (pos_ < data_.size()) {
      if (data_[pos_] == '#') {
        while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
      } else if (isSpace(data_[pos_])) {
        if (data_[pos_] == '\n') ++line_;
        ++pos_;
      } else {
        break;
      }
    }
    const size_t start = pos_;
    while (pos_ < data_.size() && !isSpace(data_[pos_]) && data_[pos_] != '#') ++pos_;
    return data_.substr(start, pos_ - start);
  }
  size_t pos() const { return pos_; }
  int line() const { return line_; }

 private:
  std::string_view data_;
  size_t pos_ = 0;
  int line_ = 1;
};

std::optional<HeightGrid> loadPgm(const TerrainSource& source, std::string_view content, Reporter& r) {
  PgmCursor cursor(content);
  const std::string_view magic = cursor.token();
  if (magic != "P2" && magic != "P5") {
    r.error(1, "not a PGM file: expected magic 'P2' or 'P5', found " + quote(magic.substr(0, 8)));
    return std::nullopt;
  }
  const bool binary = magic == "P5";

  const auto headerNumber = [&](std::string_view what, long min, long max) -> long {
    const std::string_view text = cursor.token();
    if (text.empty()) {
      r.error(cursor.line(), "PGM header ends before the " + std::string(what));
      return 0;
    }
    const std::optional<long> n = parseInteger(text);
    if (!n) {
      r.error(cursor.line(), "PGM " + std::string(what) + " must be an integer, got " + quote(text));
      return 0;
    }
    if (*n < min || *n > max) {
      r.error(cursor.line(), "PGM " + std::string(what) + " must be between " + std::to_string(min) +
                                 " and " + std::to_string(max) + ", got " + std::to_string(*n));
      return 0;
    }
    return *n;
  };
  const long columns = headerNumber("image width", kMinSamples, kMaxSamples);
  const long rows = columns ? headerNumber("image height", kMinSamples, kMaxSamples) : 0;
  const long maxval = rows ? headerNumber("maxval", 1, 65535) : 0;
  const int headerEnd = cursor.line();
  if (!(source.width > 0)) r.error(0, "width must be given (> 0) for a pgm terrain");
  if (!(source.depth > 0)) r.error(0, "depth must be given (> 0) for a pgm terrain");
  if (r.failed()) return std::nullopt;

  const long expected = columns * rows;
  std::vector<long> grey;
  grey.reserve(static_cast<size_t>(expected));
  const std::string counts = std::to_string(rows) + " rows of " + std::to_string(columns);
  if (binary) {
    // One whitespace byte ends the header; then rows*columns samples, two
    // bytes big-endian each when maxval > 255.
    if (cursor.pos() < content.size() && !isSpace(content[cursor.pos()])) {
      r.error(headerEnd, "expected one whitespace byte after the PGM maxval");
      return std::nullopt;
    }
    const size_t start = cursor.pos() + 1;
    const size_t bytesPerSample = maxval > 255 ? 2 : 1;
    const size_t rowBytes = bytesPerSample * static_cast<size_t>(columns);
    const size_t needed = rowBytes * static_cast<size_t>(rows);
    const size_t available = content.size() > start ? content.size() - start : 0;
    if (available < needed) {
      r.error(0, "pixel data ends at byte offset " + std::to_string(start + available) + " in row " +
                     std::to_string(available / rowBytes + 1) + " of " + std::to_string(rows) +
                     ": expected " + std::to_string(needed) + " bytes (" + counts + ", " +
                     (bytesPerSample == 2 ? "2 bytes" : "1 byte") + " each), found " +
                     std::to_string(available));
      return std::nullopt;
    }
    for (size_t k = 0; k < static_cast<size_t>(expected) && !r.full(); ++k) {
      const size_t offset = start + k * bytesPerSample;
      long value = static_cast<unsigned char>(content[offset]);
      if (bytesPerSample == 2) value = value * 256 + static_cast<unsigned char>(content[offset + 1]);
      if (value > maxval)
        r.error(0, "grey value " + std::to_string(value) + " exceeds maxval " + std::to_string(maxval) +
                       " at byte offset " + std::to_string(offset) + " (" +
                       rowColumn(static_cast<long>(k) / columns + 1, static_cast<long>(k) % columns + 1) +
                       ")");
      grey.push_back(value);
    }
  } else {
    // Plain: whitespace-separated decimal samples, rows may wrap lines.
    long count = 0;
    int lastLine = headerEnd;
    for (std::string_view text = cursor.token(); !text.empty() && !r.full(); text = cursor.token(), ++count) {
      lastLine = cursor.line();
      if (count == expected) {
        r.error(cursor.line(),
                "expected " + std::to_string(expected) + " grey values (" + counts + "), found more");
        break;
      }
      const long row = count / columns + 1;
      const long column = count % columns + 1;
      const std::optional<long> value = parseInteger(text);
      if (!value || *value < 0) {
        r.error(cursor.line(), quote(text) + " is not a grey value (" + rowColumn(row, column) + ")");
      } else if (*value > maxval) {
        r.error(cursor.line(), "grey value " + std::to_string(*value) + " exceeds maxval " +
                                   std::to_string(maxval) + " (" + rowColumn(row, column) + ")");
      }
      grey.push_back(value.value_or(0));
    }
    if (count < expected && !r.full())
      r.error(lastLine, "expected " + std::to_string(expected) + " grey values (" + counts + "), found " +
                            std::to_string(count));
  }
  if (r.failed()) return std::nullopt;

  std::vector<double> heights(grey.size());
  const double span = source.maxHeight - source.minHeight;
  for (size_t k = 0; k < grey.size(); ++k)
    heights[k] = source.minHeight + static_cast<double>(grey[k]) / static_cast<double>(maxval) * span;
  return gridFromNorthFirst(static_cast<int>(columns), static_cast<int>(rows), source.width, source.depth,
                            heights);
}

// ---------------------------------------------------------------------------
// CSV grid and 1-D profile

bool isSkipped(std::string_view trimmed) { return trimmed.empty() || trimmed.front() == '#'; }

std::optional<HeightGrid> loadCsvGrid(const TerrainSource& source, std::string_view content, Reporter& r) {
  if (!(source.width > 0)) r.error(0, "width must be given (> 0) for a csv grid terrain");
  if (!(source.depth > 0)) r.error(0, "depth must be given (> 0) for a csv grid terrain");

  std::vector<double> values;
  size_t columns = 0;
  int firstLine = 0;
  long rows = 0;
  for (const Line& line : splitLines(content)) {
    if (r.full()) break;
    const std::string_view text = trim(line.text);
    if (isSkipped(text)) continue;
    const std::vector<std::string_view> fields = splitCommas(text);
    if (++rows > kMaxSamples) {
      r.error(line.number, "more than " + std::to_string(kMaxSamples) + " rows");
      break;
    }
    if (columns == 0) {
      columns = fields.size();
      firstLine = line.number;
      if (!checkCount(r, line.number, "number of values per row", static_cast<long>(columns)))
        return std::nullopt;
    } else if (fields.size() != columns) {
      r.error(line.number, "expected " + std::to_string(columns) + " values as on line " +
                               std::to_string(firstLine) + ", found " + std::to_string(fields.size()));
      continue;
    }
    for (size_t k = 0; k < fields.size(); ++k) {
      const std::string where = " (column " + std::to_string(k + 1) + ")";
      if (fields[k].empty()) {
        r.error(line.number, "empty value" + where);
      } else if (const std::optional<double> v = parseDouble(fields[k])) {
        values.push_back(*v);
      } else {
        r.error(line.number, quote(fields[k]) + " is not a finite number" + where);
      }
    }
  }
  if (rows < kMinSamples && !r.full())
    r.error(0, "a csv grid needs at least " + std::to_string(kMinSamples) + " rows, found " +
                   std::to_string(rows));
  if (r.failed()) return std::nullopt;
  return gridFromNorthFirst(static_cast<int>(columns), static_cast<int>(rows), source.width, source.depth,
                            values);
}

std::optional<HeightGrid> loadProfile(const TerrainSource& source, std::string_view content, Reporter& r) {
  if (!(source.depth > 0)) r.error(0, "depth (lateral width) must be given (> 0) for a profile terrain");
  if (!(source.resolution > 0))
    r.error(0, "resolution must be > 0 for a profile terrain, got " + shortestText(source.resolution));

  std::vector<double> distance;
  std::vector<double> height;
  bool firstLine = true;
  std::string_view previousText;  // last valid distance, for messages
  int previousLine = 0;
  for (const Line& line : splitLines(content)) {
    if (r.full()) break;
    const std::string_view text = trim(line.text);
    if (isSkipped(text)) continue;
    const std::vector<std::string_view> fields = splitCommas(text);
    // A first line without any number is a column header.
    const bool header = firstLine && std::none_of(fields.begin(), fields.end(), [](std::string_view f) {
                          return parseDouble(f).has_value();
                        });
    firstLine = false;
    if (header) continue;
    if (fields.size() != 2) {
      r.error(line.number, "expected 2 values (distance,height), found " + std::to_string(fields.size()));
      continue;
    }
    const std::optional<double> d = parseDouble(fields[0]);
    const std::optional<double> h = parseDouble(fields[1]);
    if (!d) r.error(line.number, "distance " + quote(fields[0]) + " is not a finite number");
    if (!h) r.error(line.number, "height " + quote(fields[1]) + " is not a finite number");
    if (!d || !h) continue;
    if (!distance.empty() && *d <= distance.back()) {
      r.error(line.number, "distance " + std::string(fields[0]) + " does not increase (previous " +
                               std::string(previousText) + " on line " + std::to_string(previousLine) + ")");
      continue;
    }
    distance.push_back(*d);
    height.push_back(*h);
    previousText = fields[0];
    previousLine = line.number;
  }
  if (distance.size() < 2 && !r.full())
    r.error(0, "a profile needs at least 2 points, found " + std::to_string(distance.size()));
  if (r.failed()) return std::nullopt;

  // Sample counts at the requested resolution, within the limits.
  const double span = distance.back() - distance.front();
  const double width = source.width > 0 ? source.width : span;
  const auto samples = [&](double extent, std::string_view what) -> int {
    const double n = std::round(extent / source.resolution) + 1;
    if (n > kMaxSamples) {
      r.error(0, "profile " + std::string(what) + " of " + shortestText(extent) + " m at resolution " +
                     shortestText(source.resolution) + " m needs " + shortestText(n) +
                     " samples; the limit is " + std::to_string(kMaxSamples));
      return 0;
    }
    return std::max(kMinSamples, static_cast<int>(n));
  };
  const int columns = samples(width, "length");
  const int rows = samples(source.depth, "depth");
  if (r.failed()) return std::nullopt;

  // Resample the profile linearly at evenly spaced distances; a given width
  // stretches the profile span onto it.
  std::vector<double> row(static_cast<size_t>(columns));
  size_t segment = 0;
  for (int i = 0; i < columns; ++i) {
    const double s = i == columns - 1 ? distance.back() : distance.front() + span * i / (columns - 1);
    while (segment + 2 < distance.size() && s > distance[segment + 1]) ++segment;
    const double t = (s - distance[segment]) / (distance[segment + 1] - distance[segment]);
    row[static_cast<size_t>(i)] =
        height[segment] + std::clamp(t, 0.0, 1.0) * (height[segment + 1] - height[segment]);
  }
  HeightGrid grid;
  grid.columns = columns;
  grid.rows = rows;
  grid.width = width;
  grid.depth = source.depth;
  grid.heights.reserve(static_cast<size_t>(columns) * static_cast<size_t>(rows));
  for (int j = 0; j < rows; ++j) grid.heights.insert(grid.heights.end(), row.begin(), row.end());
  return grid;
}

std::optional<TerrainFormat> formatFromExtension(const std::string& path) {
  const std::string ext = toLower(std::filesystem::path(path).extension().string());
  if (ext == ".asc") return TerrainFormat::Asc;
  if (ext == ".pgm") return TerrainFormat::Pgm;
  if (ext == ".csv") return TerrainFormat::Csv;
  return std::nullopt;
}

}  // namespace

std::optional<HeightGrid> loadHeightGrid(const TerrainSource& source, Diagnostics& diag, const FileSet* files) {
  Reporter r(source.path, diag);

  std::optional<std::string> read = readSourceFile(source.path, files);
  if (!read) {
    r.error(0, "cannot open terrain file");
    return std::nullopt;
  }
  const std::string content = std::move(*read);

  // Extents from the world file: 0 means "from the terrain file".
  if (!std::isfinite(source.width) || source.width < 0)
    r.error(0, "width must be >= 0 (0 = from the file), got " + shortestText(source.width));
  if (!std::isfinite(source.depth) || source.depth < 0)
    r.error(0, "depth must be >= 0 (0 = from the file), got " + shortestText(source.depth));

  TerrainFormat format = source.format;
  if (format == TerrainFormat::Auto) {
    const std::optional<TerrainFormat> byExtension = formatFromExtension(source.path);
    if (!byExtension) {
      const std::string ext = std::filesystem::path(source.path).extension().string();
      r.error(0, (ext.empty() ? std::string("terrain file has no extension")
                              : "unknown terrain file extension " + quote(ext)) +
                     "; expected .asc, .pgm or .csv, or give the format");
      return std::nullopt;
    }
    format = *byExtension;
  }
  if (r.failed()) return std::nullopt;

  std::optional<HeightGrid> grid;
  switch (format) {
    case TerrainFormat::Asc: grid = loadAsc(source, content, r); break;
    case TerrainFormat::Pgm: grid = loadPgm(source, content, r); break;
    case TerrainFormat::Csv: grid = loadCsvGrid(source, content, r); break;
    case TerrainFormat::Profile: grid = loadProfile(source, content, r); break;
    case TerrainFormat::Auto: break;
  }
  if (!grid) return std::nullopt;
  // Plausible extents and heights (docs/formats.md): values the physics
  // engine cannot hold (a cellsize or height of 1e308) abort it.
  if (!(grid->width <= kMaxTerrainExtent && grid->depth <= kMaxTerrainExtent)) {
    r.error(0, "the terrain spans " + shortestText(grid->width) + " x " + shortestText(grid->depth) +
                   " m: at most " + shortestText(kMaxTerrainExtent) + " m a side");
    return std::nullopt;
  }
  for (double h : grid->heights)
    if (!(std::abs(h) <= kMaxTerrainHeight)) {
      r.error(0, "a height of " + shortestText(h) + " m: heights lie within +-" + shortestText(kMaxTerrainHeight) + " m");
      return std::nullopt;
    }
  return grid;
}

}  // namespace sp
