#include "app/tools/sim_tool.h"

#include <algorithm>
#include <chrono>
#include <iostream>
#include <thread>

namespace sp::simtool {

double monotonicSeconds() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

void sleepUntilSeconds(double t) {
  using namespace std::chrono;
  std::this_thread::sleep_until(steady_clock::time_point(duration_cast<steady_clock::duration>(duration<double>(t))));
}

bool endsWith(const std::string& s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Whether args[i] is one of `options` and has a value after it; says why
// not on stderr.
bool knownWithValue(const std::vector<std::string>& args, size_t i, std::initializer_list<std::string_view> options) {
  const std::string& a = args[i];
  if (std::find(options.begin(), options.end(), a) == options.end()) {
    std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
    return false;
  }
  if (i + 1 >= args.size()) {
    std::cerr << "<command line>: error: " << a << " needs a value\n";
    return false;
  }
  return true;
}

}  // namespace sp::simtool
