#pragma once
// The twin as a robot behind the link: a World stepped on its own physics
// thread, paced by the monotonic clock, taking commands at step boundaries
// and publishing its state for the server (net::RobotPort).
//
// Thread: the World lives on the physics thread alone; the RobotPort methods
// may be called from any one other thread (the server's) and exchange values
// under a short lock.

#include <atomic>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "net/robot_server.h"
#include "sim/world.h"

namespace sp {

class TwinHost : public net::RobotPort {
 public:
  /// `realTimeFactor` <= 0 runs unpaced.
  TwinHost(std::unique_ptr<World> world, double realTimeFactor);
  ~TwinHost() override;
  void start();
  void stop();

  const RobotModel* model() const override { return &model_; }
  std::string check(const Command& command) const override;
  void apply(const std::vector<Command>& commands) override;
  net::RobotState state() const override;
  std::optional<net::LaserScanState> laserAfter(uint64_t afterCount) const override;

 private:
  void run();
  void publish();

  std::unique_ptr<World> world_;
  const RobotModel model_;  // a copy: read by the server thread
  double realTimeFactor_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;  // guards the three below
  std::vector<Command> pending_;
  net::RobotState state_;
  net::LaserScanState laser_;
};

}  // namespace sp
