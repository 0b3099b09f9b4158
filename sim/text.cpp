#include "sim/text.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

namespace sp {
namespace {
constexpr std::string_view kSpace = " \t\r\n\v\f";
}

std::string_view trim(std::string_view text) {
  const size_t first = text.find_first_not_of(kSpace);
  if (first == std::string_view::npos) return {};
  const size_t last = text.find_last_not_of(kSpace);
  return text.substr(first, last - first + 1);
}

std::vector<std::string_view> splitWords(std::string_view text) {
  std::vector<std::string_view> words;
  size_t pos = 0;
  while ((pos = text.find_first_not_of(kSpace, pos)) != std::string_view::npos) {
    const size_t end = std::min(text.find_first_of(kSpace, pos), text.size());
    words.push_back(text.substr(pos, end - pos));
    pos = end;
  }
  return words;
}

std::optional<double> parseReal(std::string_view text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

std::string shortestText(double value) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value);
  return ec == std::errc() ? std::string(buf, end) : std::string("?");
}

std::string cutLongQuotes(std::string message, size_t keep) {
  const auto wordChar = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; };
  std::string out;
  size_t i = 0;
  while (i < message.size()) {
    const size_t open = message.find('\'', i);
    if (open == std::string::npos) break;
    // An opening quote does not follow a letter; a closing one is not followed by one.
    if (open > 0 && wordChar(message[open - 1])) {
      out.append(message, i, open + 1 - i);
      i = open + 1;
      continue;
    }
    size_t close = open + 1;
    while ((close = message.find('\'', close)) != std::string::npos && close + 1 < message.size() &&
           wordChar(message[close + 1]))
      ++close;
    if (close == std::string::npos) break;
    const size_t length = close - open - 1;
    out.append(message, i, open + 1 - i);
    if (length > keep) {
      size_t cut = keep;  // not inside a UTF-8 character
      while (cut > 0 && (static_cast<unsigned char>(message[open + 1 + cut]) & 0xC0) == 0x80) --cut;
      out.append(message, open + 1, cut);
      out += "\u2026' (" + std::to_string(length) + " characters)";
    } else {
      out.append(message, open + 1, length + 1);
    }
    i = close + 1;
  }
  out.append(message, std::min(i, message.size()), std::string::npos);
  return out;
}

}  // namespace sp
