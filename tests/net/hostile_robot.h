#pragma once
// A robot that lies or breaks, for tests of the console's side of the link
// (issue 58): it completes the handshake as docs/protocol.md says (or
// misbehaves in it), then plays one misbehaviour, on a thread of its own,
// for at most a bounded time. Written from the protocol alone: it shares
// the codec (net/message.h) and nothing of the robot's server.

#include <asio.hpp>

#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "net/frame.h"
#include "net/message.h"

namespace sp::test {

class HostileRobot {
 public:
  /// What the robot does once connected; `peer` writes and reads.
  class Peer {
   public:
    explicit Peer(asio::ip::tcp::socket& s, const std::atomic<bool>& stop) : socket_(s), stop_(stop) {}
    /// Writes `m` (blocking); false once the connection is gone or the test stops.
    bool send(const net::Message& m) {
      std::string error;
      const auto frame = net::encodeMessage(m, error);
      return frame && sendRaw(*frame);
    }
    bool sendRaw(const std::string& bytes) {
      if (stop_) return false;
      asio::error_code ec;
      asio::write(socket_, asio::buffer(bytes), ec);
      return !ec;
    }
    /// Reads and decodes what has arrived, without waiting; false once the
    /// connection is gone. `onMessage` (may be empty) sees each message.
    bool drain(const std::function<void(const net::Message&)>& onMessage = {}) {
      asio::error_code ec;
      while (socket_.available(ec) > 0 && !ec) {
        char buffer[8192];
        const size_t n = socket_.read_some(asio::buffer(buffer), ec);
        if (ec) return false;
        decoder_.feed(buffer, n);
        while (auto frame = decoder_.next()) {
          std::string error;
          if (auto m = net::decodeMessage(*frame, error); m && onMessage) onMessage(*m);
        }
      }
      if (ec) return false;
      // A peer that closed reads as available 0 with no error: ask once.
      char probe;
      socket_.non_blocking(true);
      const size_t n = socket_.receive(asio::buffer(&probe, 1), asio::socket_base::message_peek, ec);
      socket_.non_blocking(false);
      return !(ec == asio::error::eof || (!ec && n == 0) || (ec && ec != asio::error::would_block));
    }
    bool stopped() const { return stop_; }

   private:
    asio::ip::tcp::socket& socket_;
    const std::atomic<bool>& stop_;
    net::FrameDecoder decoder_;
  };
  using Behaviour = std::function<void(Peer&)>;

  /// How the handshake goes.
  struct Handshake {
    bool challenge = true;  ///< send a CHALLENGE on accepting
    bool welcome = true;    ///< answer the HELLO with `welcomeMsg`
    net::WelcomeMsg welcomeMsg{"hostile", 1, 50, 0.2, "", "", ""};
  };

  /// Listens on loopback; the behaviour runs on the first connection, then
  /// the connection is closed. Later connections wait in the listen queue,
  /// unanswered, until the robot is destroyed: a reconnecting client finds
  /// a robot that says nothing.
  HostileRobot(Handshake handshake, Behaviour behaviour, double limitSeconds = 20)
      : handshake_(std::move(handshake)), behaviour_(std::move(behaviour)), limit_(limitSeconds) {
    acceptor_.non_blocking(true);  // run() polls, so that stop() never waits on an accept
    thread_ = std::thread([this] { run(); });
  }
  ~HostileRobot() { stop(); }
  uint16_t port() const { return acceptor_.local_endpoint().port(); }
  /// Ends the behaviour and closes (joins the thread).
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  /// The first connection's HELLO arrived.
  bool helloSeen() const { return hello_; }
  /// The behaviour ran to its end (or was stopped).
  bool finished() const { return finished_; }

 private:
  void run() {
    asio::error_code ec;
    do {
      acceptor_.accept(socket_, ec);
      if (ec == asio::error::would_block) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    } while (ec == asio::error::would_block && !stop_);
    if (ec || stop_) return;
    socket_.non_blocking(false);
    socket_.set_option(asio::ip::tcp::no_delay(true), ec);
    Peer peer(socket_, stop_);
    if (handshake_.challenge) peer.send(net::ChallengeMsg{"0123456789abcdef0123456789abcdef"});
    const auto t0 = std::chrono::steady_clock::now();
    while (!stop_ && !hello_ && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5)) {
      if (!peer.drain([&](const net::Message& m) { hello_ = hello_ || std::holds_alternative<net::HelloMsg>(m); })) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (handshake_.welcome && hello_) peer.send(handshake_.welcomeMsg);
    // The behaviour on a thread of its own, bounded by the limit: the
    // socket is closed under it when the time is up.
    std::thread play([&] {
      behaviour_(peer);
      finished_ = true;
    });
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_);
    while (!finished_ && !stop_ && std::chrono::steady_clock::now() < end)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (finished_ && !stop_) {
      // Half-close, then read and drop what the client still sends until it
      // closes (at most 2 s): closing with its heartbeats unread would send
      // a reset, and the client's kernel would drop what it had not read of
      // ours yet (a flood's last tens of thousands of frames).
      play.join();
      socket_.shutdown(asio::ip::tcp::socket::shutdown_send, ec);
      const auto linger = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (!stop_ && std::chrono::steady_clock::now() < linger && peer.drain())
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    stop_ = true;
    socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ec);
    if (play.joinable()) play.join();
    socket_.close(ec);
  }

  Handshake handshake_;
  Behaviour behaviour_;
  double limit_;
  asio::io_context io_;
  asio::ip::tcp::acceptor acceptor_{io_, asio::ip::tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  asio::ip::tcp::socket socket_{io_};
  std::atomic<bool> stop_{false}, hello_{false}, finished_{false};
  std::thread thread_;
};

}  // namespace sp::test
