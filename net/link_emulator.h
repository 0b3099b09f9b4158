#pragma once
// Link emulation: delay, jitter, loss and bandwidth applied to the frames
// one side of the robot link sends, so that operators and tests can feel a
// planetary link (2 s ± 0.1 s) or a field radio on loopback. Used by the
// stand-in robot (net/robot_server.h) and, as an option, by the client
// (net/robot_client.h). Plain code: no sockets, no clock, no Qt; the caller
// passes the time and holds each frame until the time returned.
//
// Thread: one thread at a time; no method is thread-safe.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>

namespace sp::net {

/// What the emulated link does to each frame sent. The defaults are a
/// perfect link (every frame due at once, none lost).
struct LinkEmulatorConfig {
  double delay = 0;       ///< [s] >= 0, one-way delay added to every frame
  double jitter = 0;      ///< [s] >= 0, each delay uniform in [delay - jitter, delay + jitter], never below 0
  double loss = 0;        ///< probability in [0, 1] that a frame is dropped whole
  double bandwidth = 0;   ///< [bytes/s] frames leave one after another at this rate; 0 = unlimited
  bool keepOrder = true;  ///< a frame is never due before the one sent before it (as on TCP)
  uint64_t seed = 1;      ///< seeds the emulator's own engine: the same seed and calls give the same times

  /// Whether the link changes anything (any of delay, jitter, loss or bandwidth set).
  bool active() const { return delay > 0 || jitter > 0 || loss > 0 || bandwidth > 0; }
};

/// Decides, frame by frame, when a frame sent at `now` reaches the other end
/// or that it is lost.
///
/// Frames are dropped whole, so the stream stays a sequence of frames (TCP
/// itself never loses bytes; this emulates the robot's adapter or a radio
/// link dropping messages). With `keepOrder` (the default) due times never
/// decrease, whatever the jitter: a frame waits for the one before it, as
/// TCP would deliver them. Without it a frame may overtake an earlier one
/// when the two were sent less than 2 × jitter apart; at a spacing above
/// 2 × jitter the order is kept anyway.
///
/// Random numbers come from a std::mt19937_64 seeded from the config and
/// are turned into doubles by our own code (not std::uniform_real_distribution,
/// whose output differs between standard libraries), so the times are the
/// same on every platform.
class LinkEmulator {
 public:
  explicit LinkEmulator(LinkEmulatorConfig config = {});

  /// A frame of `bytes` bytes sent at `now` [s, any monotonic clock]:
  /// returns the time [s, same clock] at which it is due at the other end,
  /// >= now, or nullopt if it is lost. Call in the order frames are sent,
  /// with `now` not decreasing.
  std::optional<double> schedule(size_t bytes, double now);

  /// A fade (a radio outage, a tunnel): frames sent from `now` until
  /// `until` [s, same clock] leave at `until` (TCP delivers them once the
  /// link is back), then take their delay. Frames scheduled before stay as
  /// they were. Nothing random is drawn, so the times of other frames do
  /// not change.
  void fade(double until) { fadeUntil_ = std::max(fadeUntil_, until); }

  const LinkEmulatorConfig& config() const { return config_; }
  /// Replaces the config; the engine is re-seeded and the order kept with
  /// frames already scheduled.
  void setConfig(const LinkEmulatorConfig& config);

  uint64_t framesSent() const { return sent_; }        ///< frames passed to schedule()
  uint64_t framesDropped() const { return dropped_; }  ///< of those, lost
  uint64_t bytesSent() const { return bytes_; }        ///< bytes passed to schedule()

 private:
  double uniform01();  ///< [0, 1) from the engine, 53 bits

  LinkEmulatorConfig config_;
  std::mt19937_64 engine_;
  double lastDue_ = 0;     ///< due time of the last frame not lost (keepOrder)
  double linkFreeAt_ = 0;  ///< when the last frame has left (bandwidth)
  double fadeUntil_ = 0;   ///< frames sent before it leave at it (fade())
  uint64_t sent_ = 0, dropped_ = 0, bytes_ = 0;
};

}  // namespace sp::net
