#include "app/robot/line_writer.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <memory>

namespace sp {

struct LineWriter::State {
  int fd;
  std::string prefix;
  size_t capacity;
  std::mutex mutex;
  std::condition_variable wake, drained;
  std::deque<std::string> queue;
  uint64_t dropped = 0, droppedTold = 0;
  bool stopping = false;
  bool busy = false;                 // the thread is writing a batch
  std::atomic<int> owners{2};        // the LineWriter and its thread
};

LineWriter::LineWriter(int fd, std::string prefix, size_t capacity)
    : state_(new State{fd, std::move(prefix), capacity, {}, {}, {}, {}, 0, 0, false, false, {}}) {
  state_->owners = 2;
  State* s = state_;
  thread_ = std::thread([s] {
    run(*s);
    if (--s->owners == 0) delete s;
  });
}

LineWriter::~LineWriter() {
  State* s = state_;
  bool done = false;
  {
    std::unique_lock lock(s->mutex);
    s->stopping = true;
    s->wake.notify_all();
    done = s->drained.wait_for(lock, std::chrono::duration<double>(drainSeconds_),
                               [&] { return s->queue.empty() && !s->busy; });
  }
  if (done) {
    thread_.join();
  } else {
    // Still blocked in write(): left behind; it frees the state if it ever returns.
    thread_.detach();
  }
  if (--s->owners == 0) delete s;
}

void LineWriter::write(std::string line) {
  State& s = *state_;
  {
    std::lock_guard lock(s.mutex);
    if (s.queue.size() >= s.capacity) {
      ++s.dropped;
      return;
    }
    s.queue.push_back(s.prefix + line + "\n");
  }
  s.wake.notify_one();
}

uint64_t LineWriter::dropped() const {
  std::lock_guard lock(state_->mutex);
  return state_->dropped;
}

void LineWriter::run(State& s) {
  std::unique_lock lock(s.mutex);
  for (;;) {
    // Lines dropped while it was blocked are said as soon as it can write
    // again, even when no new line comes (they were never said before).
    s.wake.wait(lock, [&] { return s.stopping || !s.queue.empty() || s.dropped > s.droppedTold; });
    if (s.queue.empty() && s.dropped == s.droppedTold) {
      s.drained.notify_all();
      if (s.stopping) return;
      continue;
    }
    std::deque<std::string> batch;
    batch.swap(s.queue);
    if (s.dropped > s.droppedTold) {
      batch.push_back(s.prefix + std::to_string(s.dropped - s.droppedTold) +
                      " lines dropped: nobody was reading them\n");
      s.droppedTold = s.dropped;
    }
    s.busy = true;
    lock.unlock();
    for (const std::string& text : batch) {
      size_t done = 0;
      while (done < text.size()) {
        const ssize_t n = ::write(s.fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;  // a closed descriptor: the line is lost, the writer goes on
        done += static_cast<size_t>(n);
      }
    }
    lock.lock();
    s.busy = false;
    if (s.queue.empty()) s.drained.notify_all();
  }
}

}  // namespace sp
