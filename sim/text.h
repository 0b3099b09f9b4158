#pragma once
// Small text helpers shared by the file readers of sim/: locale-independent
// number parsing and printing, trimming and splitting.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sp {

/// `text` without leading and trailing white space.
std::string_view trim(std::string_view text);

/// The white-space separated words of `text`.
std::vector<std::string_view> splitWords(std::string_view text);

/// A finite decimal number and nothing else, independent of the locale; as in
/// robot and world files: no '+', no inf or nan, no units.
std::optional<double> parseReal(std::string_view text);

/// The shortest text that reads back to exactly `value`.
std::string shortestText(double value);

}  // namespace sp
