#pragma once
// Lines for the operator (connections, refusals, lease changes), written to
// a file descriptor by a thread of their own, so that whoever produces them
// never waits for the terminal or pipe behind it: the robot link's thread,
// which also runs the deadman, must not stop when nobody reads stderr (a
// full pipe, a paused terminal). When the queue is full, lines are dropped
// and counted; the count is written once the writer catches up.
//
// Thread: write() from any thread; the constructor and destructor belong to
// the owner's.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

namespace sp {

class LineWriter {
 public:
  /// Writes to `fd` (not owned), each line prefixed with `prefix` and ended
  /// with a newline; at most `capacity` lines wait.
  LineWriter(int fd, std::string prefix, size_t capacity = 4096);
  /// Gives the writer up to `drainSeconds` to write what is queued, then
  /// leaves it behind if the descriptor still blocks (the process is
  /// ending; it must not hang on a reader that never comes).
  ~LineWriter();
  LineWriter(const LineWriter&) = delete;
  LineWriter& operator=(const LineWriter&) = delete;

  /// Queues one line; never blocks on the descriptor.
  void write(std::string line);
  /// Lines dropped so far because the queue was full.
  uint64_t dropped() const;

 private:
  struct State;
  static void run(State& state);
  State* state_;  // shared with the thread; freed by whichever ends last
  std::thread thread_;
  double drainSeconds_ = 0.5;
};

}  // namespace sp
