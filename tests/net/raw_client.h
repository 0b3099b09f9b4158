#pragma once
// A blocking link client for tests, on a raw loopback socket: frames in and
// out with timeouts, and nothing of RobotClient's own behaviour (no
// keep-alives of its own: a test decides when it goes silent).

#include <QTest>

#include <asio.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <thread>

#include "net/auth.h"
#include "net/frame.h"
#include "net/message.h"

namespace sp::test {

using namespace sp::net;
using Clock = std::chrono::steady_clock;

inline const std::string kToken = "00112233445566778899aabbccddeeff";

inline double seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

/// A blocking client for tests: frames in and out, with timeouts.
struct RawClient {
  asio::io_context io;
  asio::ip::tcp::socket socket{io};
  FrameDecoder decoder;
  bool eof = false;

  explicit RawClient(uint16_t port) {
    socket.connect({asio::ip::make_address("127.0.0.1"), port});
    socket.set_option(asio::ip::tcp::no_delay(true));  // as RobotClient: small frames leave at once
    socket.non_blocking(true);
  }
  void send(const Message& m) {
    std::string error;
    const auto frame = encodeMessage(m, error);
    if (!frame) qFatal("%s", error.c_str());
    asio::error_code ec;
    asio::write(socket, asio::buffer(*frame), ec);
  }
  void sendRaw(const std::string& bytes) {
    asio::error_code ec;
    asio::write(socket, asio::buffer(bytes), ec);
  }
  /// The next message within `timeout` seconds, or nullopt.
  std::optional<Message> next(double timeout) {
    const auto t0 = Clock::now();
    while (true) {
      if (auto frame = decoder.next()) {
        std::string error;
        return decodeMessage(*frame, error);
      }
      if (eof || seconds(t0) > timeout) return std::nullopt;
      char buf[4096];
      asio::error_code ec;
      const size_t n = socket.read_some(asio::buffer(buf), ec);
      if (ec == asio::error::would_block) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      if (ec) {
        eof = true;
        continue;
      }
      decoder.feed(buf, n);
    }
  }
  /// Waits for a message of type T (skipping others) within `timeout`.
  template <typename T>
  std::optional<T> waitFor(double timeout) {
    const auto t0 = Clock::now();
    while (seconds(t0) < timeout) {
      auto m = next(timeout - seconds(t0));
      if (!m) return std::nullopt;
      if (auto* t = std::get_if<T>(&*m)) return *t;
    }
    return std::nullopt;
  }
  /// The next failsafe EVENT within `timeout` seconds while keeping the
  /// lease alive every `period` seconds (so the deadman stays quiet), or
  /// nullopt; other messages are skipped.
  std::optional<EventMsg> failsafeWhileKeepingAlive(double timeout, double period) {
    const auto t0 = Clock::now();
    while (seconds(t0) < timeout) {
      send(LeaseKeepaliveMsg{});
      if (auto e = waitFor<EventMsg>(period); e && e->kind == EventKind::Failsafe) return e;
    }
    return std::nullopt;
  }
  /// The HELLO that answers this connection's CHALLENGE with a proof of `token`.
  HelloMsg provingHello(Role role, const std::string& name, const std::string& token = kToken) {
    const auto challenge = waitFor<ChallengeMsg>(3.0);
    if (!challenge) return HelloMsg{name, {}, role, std::string(64, '0')};
    return HelloMsg{name, {}, role, helloProof(token, challenge->nonce, name, role)};
  }
  void hello(Role role, const std::string& name) {
    send(provingHello(role, name));
    QVERIFY(waitFor<WelcomeMsg>(2.0));
  }
};


}  // namespace sp::test
