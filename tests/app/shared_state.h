#pragma once
// State that a client's callbacks (on its own thread) fill and the test's
// thread waits on: derive, add fields, change them with add() and wait with
// waitFor().

#include <chrono>
#include <condition_variable>
#include <mutex>

namespace sp::test {

struct SharedState {
  std::mutex mutex;
  std::condition_variable cv;

  /// Runs `change` under the lock, then wakes the waiters.
  template <typename F>
  void add(F change) {
    {
      std::lock_guard lock(mutex);
      change();
    }
    cv.notify_all();
  }
  /// `get()` under the lock: reads what the callbacks' thread may be writing.
  template <typename F>
  auto read(F get) {
    std::lock_guard lock(mutex);
    return get();
  }
  /// Waits until `pred` holds (checked under the lock) or `limit` passes.
  template <typename P>
  bool waitFor(P pred, std::chrono::milliseconds limit = std::chrono::seconds(5)) {
    std::unique_lock lock(mutex);
    return cv.wait_for(lock, limit, pred);
  }
};

}  // namespace sp::test
