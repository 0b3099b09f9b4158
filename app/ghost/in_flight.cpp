#include "app/ghost/in_flight.h"

namespace sp {

uint64_t InFlightCommands::add(const Command& command, double time) {
  commands_.push_back({next_, time, command});
  return next_++;
}

std::vector<SentCommand> InFlightCommands::from(uint64_t seq) const {
  std::vector<SentCommand> out;
  for (const SentCommand& c : commands_)
    if (c.seq >= seq) out.push_back(c);
  return out;
}

void InFlightCommands::forgetBefore(double time) {
  while (!commands_.empty() && commands_.front().time < time) {
    const Command& c = commands_.front().command;
    if (std::holds_alternative<DriveCmd>(c) || std::holds_alternative<StopCmd>(c)) lastDrive_ = commands_.front();
    commands_.pop_front();
  }
}

std::vector<std::pair<double, Command>> InFlightCommands::upTo(double upTo) const {
  std::vector<std::pair<double, Command>> out;
  if (lastDrive_) out.emplace_back(lastDrive_->time, lastDrive_->command);
  for (const SentCommand& c : commands_) {
    if (c.time > upTo) break;
    // A terrain patch moves no base and carries its heights: not copied
    // for the region's scale every frame.
    if (!std::holds_alternative<TerrainPatchCmd>(c.command)) out.emplace_back(c.time, c.command);
  }
  return out;
}

}  // namespace sp
