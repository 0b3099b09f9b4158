#pragma once
// simpartner-sim's subcommands, a file each (sim_<command>.cpp), and what
// they share; main() and the usage text are in sim_main.cpp. Each returns
// the program's exit code (docs/formats.md names them per command).

#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace sp::simtool {

using Args = std::vector<std::string>;

/// The usage text (--help): every command and option.
extern const char* const kUsage;

int check(const Args& files);
int printParams();
int validate(const Args& args);
int run(const Args& args);
int rehearseCommand(const Args& args);
int resim(const Args& args);
int exportLog(const Args& args, const char* argv0);
int urdfCommand(const Args& args);
int calibrate(const Args& args);
int sweepCommand(const Args& args, const char* argv0);
int sweepTaskCommand(const Args& args);
int collectCommand(const Args& args);

/// [s] the steady clock, and a sleep until a time of it.
double monotonicSeconds();
void sleepUntilSeconds(double t);
bool endsWith(const std::string& s, std::string_view suffix);
/// Whether args[i] is one of `options` and has a value after it; says why
/// not on stderr.
bool knownWithValue(const std::vector<std::string>& args, size_t i, std::initializer_list<std::string_view> options);

}  // namespace sp::simtool
