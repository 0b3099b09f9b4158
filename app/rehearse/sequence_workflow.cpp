// One command sequence's way from text to the robot (sequence_workflow.h).
#include "app/rehearse/sequence_workflow.h"

#include <algorithm>
#include <cmath>

#include "app/rehearse/sequence_relay.h"
#include "sim/command_file.h"
#include "sim/text.h"

namespace sp {

void SequenceWorkflow::check(const std::string& text, const WorldModel* world) {
  problems_.clear();
  if (!world || world->robots.empty()) return;
  const RobotModel& robot = world->robots[0].model;
  Diagnostics diag;
  const auto commands = parseCommandSequence(text, "sequence", diag, &robot);
  if (commands) checkCommands(*commands, *world, "sequence", diag);  // terrain edits against its grid
  for (const Diagnostic& d : diag.items())
    if (d.severity == Severity::Error) problems_.push_back({d.line, d.message});
}

std::optional<RehearsalPlan> SequenceWorkflow::plan(const std::string& text, const WorldModel* world,
                                                    const SimParams& params, const FlightRules& rules,
                                                    std::optional<RehearsalStart> robotStart, std::string& why) const {
  if (pinned_) world = &pinned_->world;
  if (!world || world->robots.empty()) {
    why = "no world with a robot to rehearse on";
    return std::nullopt;
  }
  Diagnostics diag;
  auto commands = parseCommandSequence(text, "sequence", diag, &world->robots[0].model);
  if (!commands || commands->empty()) {
    why = "the sequence has no command";
    return std::nullopt;
  }
  return RehearsalPlan{*world, pinned_ ? pinned_->params : params, rules, std::move(*commands),
                       pinned_ ? std::optional(pinned_->start) : std::move(robotStart)};
}

void SequenceWorkflow::previewed(RehearsalPlan plan, RehearsalResult result) {
  plan_ = std::move(plan);
  result_ = std::move(result);
  robust_.reset();
}

void SequenceWorkflow::rehearsed(RehearsalPlan plan, RehearsalResult result, std::string text, bool pinned) {
  plan_ = std::move(plan);
  result_ = std::move(result);
  robust_.reset();
  rehearsedText_ = std::move(text);
  planPinned_ = pinned;
  terrainEditedSince_ = false;
}

void SequenceWorkflow::forget() {
  plan_.reset();
  result_.reset();
  robust_.reset();
}

bool SequenceWorkflow::terrainEdited() {
  if (!result_ || terrainEditedSince_) return false;
  terrainEditedSince_ = true;
  return true;
}

bool SequenceWorkflow::current(const std::string& text) const {
  return result_ && rehearsedText_ == text && !terrainEditedSince_;
}

std::string SequenceWorkflow::sendRefusal(const std::string& text, bool linkReady) const {
  if (!plan_ || !result_) return "rehearse the sequence first";
  if (terrainEditedSince_) return "the terrain was edited since the rehearsal: rehearse it again";
  if (!current(text)) return "the sequence changed since its rehearsal: rehearse it again";
  if (!result_->passed) return "the rehearsal failed (" + result_->summary() + ")";
  if (planPinned_) return "it was rehearsed from a logged moment, not from the robot's state: rehearse it from the robot";
  if (!linkReady) return "the robot cannot take a sequence now (not connected, no lease, or latched)";
  return {};
}

std::optional<net::SequenceMsg> SequenceWorkflow::message(std::string& why) const {
  if (!plan_ || !result_) {
    why = "rehearse the sequence first";
    return std::nullopt;
  }
  return sequenceMessage(*plan_, *result_, why);
}

std::vector<Vec3> SequenceWorkflow::path() const {
  std::vector<Vec3> path;
  if (result_)
    for (const RehearsalSample& s : result_->path) path.push_back(s.base.p);
  return path;
}

std::vector<double> SequenceWorkflow::band() const {
  if (!robust_ || !result_) return {};
  std::vector<double> out;
  out.reserve(result_->path.size());
  std::vector<double> d;
  for (size_t k = 0; k < result_->path.size(); ++k) {
    // The runs sample the same instants as the rehearsal (every
    // kSampleInterval from the start): the k-th point of each is this time's.
    const Vec3 at = result_->path[k].base.p;
    d.clear();
    for (const std::vector<Vec3>& p : robust_->paths)
      if (k < p.size()) d.push_back(std::hypot(p[k].x - at.x, p[k].y - at.y));
    if (d.size() < 2) {
      out.push_back(0);
      continue;
    }
    std::sort(d.begin(), d.end());
    out.push_back(d[std::min(d.size() - 1, static_cast<size_t>(std::ceil(0.9 * static_cast<double>(d.size()))) - 1)]);
  }
  return out;
}

std::vector<Vec3> SequenceWorkflow::envelope() const {
  if (!robust_) return {};
  std::vector<Vec3> ends;
  for (const Pose& p : robust_->endPoses) ends.push_back(p.p);
  std::vector<Vec3> hull = convexHullXY(ends);
  if (!hull.empty()) hull.push_back(hull.front());  // closed
  return hull;
}

std::string SequenceWorkflow::rehearsalLogLine() const {
  if (!plan_ || !result_) return {};
  const RobotModel& robot = plan_->world.robots[0].model;
  return sequenceHash(sequenceText(plan_->commands, &robot)) + " " + (result_->passed ? "passed" : "failed") + " (" +
         std::to_string(plan_->commands.size()) + " commands, " + shortestText(result_->duration) +
         " s simulated): " + result_->summary();
}

std::string SequenceWorkflow::robustnessLogLine() const {
  if (!robust_) return {};
  return "robustness: " + robust_->verdict() + " (end spread " + shortestText(robust_->spread) + " m)";
}

}  // namespace sp
