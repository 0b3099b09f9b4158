#pragma once
// Diagnostics collected while reading files: every problem of a file in one
// pass, each as `file:line: error: message` (Drake's DiagnosticDetail style).

#include <string>
#include <string_view>
#include <vector>

namespace sp {

enum class Severity { Warning, Error };

/// One problem found in an input. `line` is 1-based; 0 when the problem
/// concerns the file as a whole (it cannot be opened, say).
struct Diagnostic {
  std::string file;
  int line = 0;
  Severity severity = Severity::Error;
  std::string message;

  /// `file:line: error: message`, or `file: error: message` when line is 0.
  std::string format() const;
};

/// An ordered list of diagnostics. Loaders append to it and never stop at the
/// first error. Not thread-safe; owned by one caller.
class Diagnostics {
 public:
  void error(std::string_view file, int line, std::string message);
  void warning(std::string_view file, int line, std::string message);
  void append(const Diagnostics& other);

  bool hasErrors() const { return errorCount_ > 0; }
  int errorCount() const { return errorCount_; }
  bool empty() const { return items_.empty(); }
  const std::vector<Diagnostic>& items() const { return items_; }

  /// All diagnostics, one formatted line each, newline-terminated.
  std::string format() const;

 private:
  std::vector<Diagnostic> items_;
  int errorCount_ = 0;
};

}  // namespace sp
