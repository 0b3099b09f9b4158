#pragma once
// The console's built-in jobs, in the order their docks are laid out, and
// their command-line options. A new job is a folder under ui/jobs/ and one
// line in jobs.cpp; the window is not edited (ui/console_context.h), nor
// is the console's command line (a job declares its own options).

#include <QString>

#include <memory>
#include <vector>

#include "ui/console_context.h"

QT_FORWARD_DECLARE_CLASS(QCommandLineParser)

namespace sp {

/// The built-in jobs, with their defaults until they take a command line.
ConsoleJobs builtInJobs();
/// Adds every job's command-line options to `parser`.
void addJobOptions(QCommandLineParser& parser, const ConsoleJobs& jobs);
/// Hands the parsed command line to every job: "" or the first one's
/// complaint ("x.rules: error: not found; looked in ...").
QString takeJobOptions(const QCommandLineParser& parser, const ConsoleJobs& jobs);

}  // namespace sp
