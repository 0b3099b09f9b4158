#include "sim/diagnostics.h"

#include "sim/text.h"

namespace sp {

std::string Diagnostic::format() const {
  std::string out = file;
  if (line > 0) out += ":" + std::to_string(line);
  out += severity == Severity::Error ? ": error: " : ": warning: ";
  out += message;
  return out;
}

void Diagnostics::error(std::string_view file, int line, std::string message) {
  items_.push_back({std::string(file), line, Severity::Error, cutLongQuotes(std::move(message))});
  ++errorCount_;
}

void Diagnostics::warning(std::string_view file, int line, std::string message) {
  items_.push_back({std::string(file), line, Severity::Warning, cutLongQuotes(std::move(message))});
}

void Diagnostics::append(const Diagnostics& other) {
  for (const Diagnostic& d : other.items_) items_.push_back(d);
  errorCount_ += other.errorCount_;
}

std::string Diagnostics::format() const {
  std::string out;
  for (const Diagnostic& d : items_) out += d.format() + "\n";
  return out;
}

}  // namespace sp
