#include "sim/properties.h"

#include <map>
#include <string>

#include "sim/text.h"

namespace sp {

bool readProperties(std::string_view contents, std::string_view path, Diagnostics& diag,
                    const std::function<bool(std::string_view key)>& known,
                    const std::function<bool(std::string_view key, std::string_view value, int line)>& set) {
  std::map<std::string, int, std::less<>> firstLine;
  bool ok = true;
  int line = 0;
  for (size_t pos = 0; pos < contents.size();) {
    size_t end = contents.find('\n', pos);
    if (end == std::string_view::npos) end = contents.size();
    std::string_view text = contents.substr(pos, end - pos);
    pos = end + 1;
    ++line;
    text = trim(text.substr(0, text.find('#')));
    if (text.empty()) continue;
    const size_t eq = text.find('=');
    const std::string_view key = eq == std::string_view::npos ? std::string_view() : trim(text.substr(0, eq));
    const std::string_view value = eq == std::string_view::npos ? std::string_view() : trim(text.substr(eq + 1));
    if (key.empty() || value.empty()) {
      diag.error(path, line, "expected 'key = value'");
      ok = false;
      continue;
    }
    if (const auto it = firstLine.find(key); it != firstLine.end()) {
      diag.error(path, line, "duplicate key '" + std::string(key) + "' (first set on line " +
                                 std::to_string(it->second) + ")");
      ok = false;
      continue;
    }
    if (known(key)) firstLine.emplace(std::string(key), line);
    if (!set(key, value, line)) ok = false;
  }
  return ok;
}

}  // namespace sp
