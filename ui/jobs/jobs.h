#pragma once
// The console's built-in jobs, in the order their docks are laid out. A new
// job is a folder under ui/jobs/ and one line in jobs.cpp; the window is
// not edited (ui/console_context.h).

#include <QString>

#include <memory>
#include <vector>

#include "ui/console_context.h"

namespace sp {

struct ConsoleOptions;

/// The built-in jobs for a console started with `options`; `logDir` is
/// where its session logs go.
std::vector<std::unique_ptr<ConsoleJob>> builtInJobs(const ConsoleOptions& options, const QString& logDir);

}  // namespace sp
