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
  while (!commands_.empty() && commands_.front().time < time) commands_.pop_front();
}

}  // namespace sp
