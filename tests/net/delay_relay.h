#pragma once
// A TCP relay on loopback that holds every byte for a one-way delay (plus
// uniform jitter, order kept) in each direction: a slow link as the robot
// meets it through a tunnel or a long-haul route, outside the robot's own
// link emulation (which the robot knows about). Real sockets both sides.

#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace sp::test {

class DelayRelay {
 public:
  DelayRelay(uint16_t target, double delay, double jitter, uint64_t seed = 1)
      : target_(target), delay_(delay), jitter_(jitter), random_(seed) {
    listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a = loopback(0);
    ::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(listener_, 64);
    socklen_t n = sizeof a;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &n);
    port_ = ntohs(a.sin_port);
    accepter_ = std::thread([this] { acceptLoop(); });
  }
  ~DelayRelay() {
    stop_ = true;
    accepter_.join();
    for (auto& p : pumps_) p->join();
    for (int s : sockets_) ::close(s);
    ::close(listener_);
  }
  DelayRelay(const DelayRelay&) = delete;
  DelayRelay& operator=(const DelayRelay&) = delete;

  uint16_t port() const { return port_; }

 private:
  using Clock = std::chrono::steady_clock;

  static sockaddr_in loopback(uint16_t port) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port);
    return a;
  }

  // One direction: a reader takes bytes as they come, a writer hands each
  // chunk on at its delivery time (an empty chunk: the sender closed).
  class Pump {
   public:
    Pump(DelayRelay& relay, int from, int to) : relay_(relay), from_(from), to_(to) {
      reader_ = std::thread([this] { read(); });
      writer_ = std::thread([this] { write(); });
    }
    void join() {
      reader_.join();
      writer_.join();
    }

   private:
    struct Chunk {
      Clock::time_point at;
      std::string bytes;
    };
    void read() {
      char buf[4096];
      for (;;) {
        pollfd p{from_, POLLIN, 0};
        if (relay_.stop_) break;
        if (::poll(&p, 1, 20) <= 0) continue;
        const ssize_t n = ::recv(from_, buf, sizeof buf, 0);
        push(n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string());
        if (n <= 0) return;
      }
      push({});
    }
    void push(std::string bytes) {
      std::lock_guard lock(mutex_);
      const auto at = std::max(last_, Clock::now() + relay_.draw());
      last_ = at;
      queue_.push_back({at, std::move(bytes)});
      wake_.notify_one();
    }
    void write() {
      for (;;) {
        std::unique_lock lock(mutex_);
        wake_.wait(lock, [&] { return !queue_.empty(); });
        const Chunk c = queue_.front();
        lock.unlock();
        std::this_thread::sleep_until(c.at);
        lock.lock();
        queue_.pop_front();
        lock.unlock();
        if (c.bytes.empty()) {
          ::shutdown(to_, SHUT_WR);
          return;
        }
        for (size_t done = 0; done < c.bytes.size();) {
          const ssize_t n = ::send(to_, c.bytes.data() + done, c.bytes.size() - done, MSG_NOSIGNAL);
          if (n <= 0) return;
          done += static_cast<size_t>(n);
        }
      }
    }
    DelayRelay& relay_;
    const int from_, to_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<Chunk> queue_;
    Clock::time_point last_{};
    std::thread reader_, writer_;
  };

  Clock::duration draw() {
    std::lock_guard lock(randomMutex_);
    std::uniform_real_distribution<double> u(-jitter_, jitter_);
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, delay_ + u(random_))));
  }

  void acceptLoop() {
    while (!stop_) {
      pollfd p{listener_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      const int client = ::accept(listener_, nullptr, nullptr);
      if (client < 0) continue;
      const int robot = ::socket(AF_INET, SOCK_STREAM, 0);
      sockaddr_in a = loopback(target_);
      if (::connect(robot, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(client);
        ::close(robot);
        continue;
      }
      sockets_.push_back(client);
      sockets_.push_back(robot);
      pumps_.push_back(std::make_unique<Pump>(*this, client, robot));
      pumps_.push_back(std::make_unique<Pump>(*this, robot, client));
    }
    for (int s : sockets_) ::shutdown(s, SHUT_RDWR);
  }

  const uint16_t target_;
  const double delay_, jitter_;
  std::mt19937_64 random_;
  std::mutex randomMutex_;
  int listener_ = -1;
  uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread accepter_;
  std::vector<std::unique_ptr<Pump>> pumps_;  // only the accepter adds, before the destructor joins
  std::vector<int> sockets_;
};

}  // namespace sp::test
