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

/// `message` with every quoted value ('...') longer than `keep` characters
/// cut to its first `keep` and its length: `'aaaa…' (5000000 characters)`.
/// An error must not echo a 5 MB value. An apostrophe inside a word
/// ("robot's") is not a quote.
std::string cutLongQuotes(std::string message, size_t keep = 80);

}  // namespace sp
