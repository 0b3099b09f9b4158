#pragma once
// `simpartner-robot` as a child process for the tests that need a whole
// program (signals, a blocked stderr): spawn it with its output on pipes and
// read the port it listens on.

#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include <chrono>
#include <string>
#include <vector>

extern char** environ;

namespace sp::test {

/// Spawns SP_ROBOT_EXE with `args` (after the program name), stdout on
/// `out` and stderr on `err` (-1: inherited). 0 when it could not start.
inline pid_t spawnRobot(std::vector<std::string> args, int out, int err = -1) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out, 1);
  if (err >= 0) posix_spawn_file_actions_adddup2(&actions, err, 2);
  args.insert(args.begin(), SP_ROBOT_EXE);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, SP_ROBOT_EXE, &actions, nullptr, argv.data(), environ) != 0) pid = 0;
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

/// Kills and reaps the child when a test returns early (a failed QVERIFY),
/// so no robot outlives its test; release() once the test reaped it itself.
class ChildReaper {
 public:
  explicit ChildReaper(pid_t pid) : pid_(pid) {}
  ChildReaper(const ChildReaper&) = delete;
  ChildReaper& operator=(const ChildReaper&) = delete;
  ~ChildReaper() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  void release() { pid_ = 0; }

 private:
  pid_t pid_;
};

/// The port from the robot's stdout (`fd`): its "listening on 127.0.0.1:PORT"
/// line, within `timeout`; 0 if none came. `text` gets what was read.
inline uint16_t listeningPort(int fd, std::string& text, std::chrono::seconds timeout = std::chrono::seconds(10)) {
  for (auto until = std::chrono::steady_clock::now() + timeout; std::chrono::steady_clock::now() < until;) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    char buf[256];
    const ssize_t n = read(fd, buf, sizeof buf);
    if (n <= 0) break;
    text.append(buf, static_cast<size_t>(n));
    if (const size_t at = text.find("listening on 127.0.0.1:"); at != std::string::npos && text.find('\n', at) != std::string::npos)
      return static_cast<uint16_t>(std::stoi(text.substr(at + 23)));
  }
  return 0;
}

}  // namespace sp::test
