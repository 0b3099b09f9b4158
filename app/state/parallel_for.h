#pragma once
// One parallel-for for the sweeps, the robustness runs and calibration's
// candidate twins: each is many independent twin runs on the cores.
//
// Thread: body(i) runs on up to `threads` threads at once (the caller's one
// of them) and must touch only what index i owns.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace sp {

/// Calls body(i) once for each i in [0, n), in no set order, on up to
/// `threads` threads (at least the caller's; no more than n). A body that
/// returns false stops the handing out of indices not yet begun (those
/// begun finish). A body that throws stops it too, and the first exception
/// is rethrown here once every thread has finished (a throw on a pool
/// thread would end the process).
template <class Body>
void parallelFor(size_t n, int threads, Body&& body) {
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr failure;
  std::mutex failureMutex;
  const auto work = [&] {
    for (size_t i; !stop && (i = next++) < n;) {
      try {
        if (!body(i)) stop = true;
      } catch (...) {
        std::lock_guard lock(failureMutex);
        if (!failure) failure = std::current_exception();
        stop = true;
      }
    }
  };
  std::vector<std::thread> pool;
  const size_t wanted = std::min(n, static_cast<size_t>(std::max(1, threads)));
  for (size_t t = 1; t < wanted; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace sp
