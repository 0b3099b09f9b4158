#pragma once
// Reading a sweep's results.csv in the sweep tests (tst_sweep, tst_sweep_slurm).

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace sp::test {

inline std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The end hash of every sample that ran, in index order (results.csv's
/// second-to-last column).
inline std::vector<std::string> sweepHashes(const std::string& dir) {
  std::vector<std::string> out;
  std::istringstream in(readText(dir + "/results.csv"));
  std::string line;
  std::getline(in, line);
  for (; std::getline(in, line);) {
    const size_t last = line.rfind(','), before = line.rfind(',', last - 1);
    out.push_back(line.substr(before + 1, last - before - 1));
  }
  return out;
}

}  // namespace sp::test
