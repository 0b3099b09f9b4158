#pragma once
// How the ghost's stages meet (app/ghost/ghost.h): each stage publishes its
// newest output in a slot of its own, which the next stage takes when it is
// ready (older outputs are dropped, never queued), and rings that stage's
// doorbell. No lock is held while waiting or computing, and none is held
// while taking another, so no stage waits on a stage that computes.
//
// Thread: any; a Slot's and a Doorbell's own mutex guards it.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <utility>

namespace sp::ghost_detail {

/// The newest value of one stage's output, with a version counting publishes.
template <class T>
class Slot {
 public:
  void publish(std::shared_ptr<const T> value) {
    std::lock_guard lock(mutex_);
    value_ = std::move(value);
    ++version_;
  }
  /// The value and its version (null and 0 before the first publish).
  std::pair<uint64_t, std::shared_ptr<const T>> latest() const {
    std::lock_guard lock(mutex_);
    return {version_, value_};
  }
  uint64_t version() const {
    std::lock_guard lock(mutex_);
    return version_;
  }

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const T> value_;
  uint64_t version_ = 0;
};

/// A thread's doorbell: rung when something it consumes changed; closed
/// when the ghost ends.
class Doorbell {
 public:
  using Clock = std::chrono::steady_clock;
  void ring() {
    {
      std::lock_guard lock(mutex_);
      ++rings_;
    }
    cv_.notify_one();
  }
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }
  bool closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
  }
  /// Waits until rung since `seen` (updated), closed or `until`; false when closed.
  bool waitUntil(uint64_t& seen, Clock::time_point until) {
    std::unique_lock lock(mutex_);
    cv_.wait_until(lock, until, [&] { return closed_ || rings_ != seen; });
    seen = rings_;
    return !closed_;
  }
  /// Waits until rung since `seen` (updated) or closed; false when closed.
  bool wait(uint64_t& seen) {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return closed_ || rings_ != seen; });
    seen = rings_;
    return !closed_;
  }
  /// Sleeps until `until` unless closed first; false when closed.
  bool sleepUntil(Clock::time_point until) {
    std::unique_lock lock(mutex_);
    cv_.wait_until(lock, until, [&] { return closed_; });
    return !closed_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  uint64_t rings_ = 0;
  bool closed_ = false;
};

}  // namespace sp::ghost_detail
