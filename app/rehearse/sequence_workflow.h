#pragma once
// One command sequence's way from text to the robot, without Qt: what the
// text's problems are, where a rehearsal starts (the robot's state now, or
// a logged moment pinned from a replay: a what-if), what was rehearsed and
// whether it is still the text and the terrain, and the gate Send passes
// through. The Sequence dock (ui/jobs/sequence/) shows it and runs the
// rehearsals on its worker; tests drive it directly.
//
//   SequenceWorkflow flow;
//   flow.check(text, world);                       // problems(): line and message
//   auto plan = flow.plan(text, world, params, rules, robotStart, why);
//   ... rehearse(*plan) on a worker ...
//   flow.rehearsed(std::move(*plan), result, text);
//   if (flow.sendRefusal(text, linkReady).empty()) send(*flow.message(why));
//
// Thread: one thread at a time (the GUI's); rehearsals run elsewhere on the
// plans it hands out, and their results are handed back.

#include <optional>
#include <string>
#include <vector>

#include "app/rehearse/rehearsal.h"
#include "net/message.h"
#include "sim/flight_rules.h"

namespace sp {

class SequenceWorkflow {
 public:
  /// A problem of the text: its line (1-based; 0 = the whole text) and what.
  struct Problem {
    int line = 0;
    std::string message;
  };
  /// A logged moment rehearsals start from instead of the robot (a what-if).
  struct Pinned {
    RehearsalStart start;
    WorldModel world;
    SimParams params;
    std::string label;  ///< for the operator ("the log foo.sqlite at 12.3 s")
  };

  /// Checks `text` against `world`'s robot (its limits, terrain edits
  /// against its grid); problems() holds what is wrong. Without a world with
  /// a robot nothing can be judged: no problems.
  void check(const std::string& text, const WorldModel* world);
  const std::vector<Problem>& problems() const { return problems_; }

  void pin(Pinned pinned) { pinned_ = std::move(pinned); }
  void unpin() { pinned_.reset(); }
  const std::optional<Pinned>& pinned() const { return pinned_; }

  /// The rehearsal of `text` to run now: in the pinned world from the
  /// pinned moment, else in `world` with `params` from `robotStart` (nullopt:
  /// the world's start). nullopt and `why` when there is nothing to rehearse.
  std::optional<RehearsalPlan> plan(const std::string& text, const WorldModel* world, const SimParams& params,
                                    const FlightRules& rules, std::optional<RehearsalStart> robotStart,
                                    std::string& why) const;

  /// The fast profile's first verdicts for `plan` (shown while the full
  /// rehearsal runs; never sent).
  void previewed(RehearsalPlan plan, RehearsalResult result);
  /// The full-fidelity rehearsal of `text` (the one Send relays) ended;
  /// `pinned`: it started from the pinned moment.
  void rehearsed(RehearsalPlan plan, RehearsalResult result, std::string text, bool pinned);
  /// The robustness rehearsals of the current plan ended.
  void robustnessDone(RobustnessResult result) { robust_ = std::move(result); }
  /// The world changed: the last rehearsal is of another world.
  void forget();
  /// The terrain was edited: the last rehearsal ran on the old heights.
  /// True when that makes a rehearsal stale that was current.
  bool terrainEdited();
  bool terrainEditedSince() const { return terrainEditedSince_; }

  const std::optional<RehearsalPlan>& rehearsedPlan() const { return plan_; }
  const std::optional<RehearsalResult>& result() const { return result_; }
  const std::optional<RobustnessResult>& robustness() const { return robust_; }
  bool rehearsedFromPin() const { return planPinned_; }
  /// There is a rehearsal of exactly `text` on the terrain as it is.
  bool current(const std::string& text) const;

  /// "" when the rehearsed sequence may go to the robot now (`linkReady`:
  /// connected, holding the lease, nothing latched), else why not.
  std::string sendRefusal(const std::string& text, bool linkReady) const;
  /// The SEQUENCE message of the rehearsed plan (after sendRefusal() was
  /// ""); nullopt and `why` when the rehearsal cannot be relayed.
  std::optional<net::SequenceMsg> message(std::string& why) const;

  /// The rehearsed path on the ground, and the robustness runs' end
  /// positions' hull, closed (empty without them).
  std::vector<Vec3> path() const;
  std::vector<Vec3> envelope() const;
  /// The session log's lines: the rehearsal's ("<hash> passed (3 commands,
  /// 12 s simulated): ...") and the robustness runs'.
  std::string rehearsalLogLine() const;
  /// The rehearsed path's band: per path() point, the radius within which
  /// 90 % of the robustness runs were at that time (those still running);
  /// empty before robustness runs, 0 where fewer than two ran.
  std::vector<double> band() const;
  std::string robustnessLogLine() const;

 private:
  std::vector<Problem> problems_;
  std::optional<Pinned> pinned_;
  std::optional<RehearsalPlan> plan_;  // of result_
  std::optional<RehearsalResult> result_;
  std::optional<RobustnessResult> robust_;
  std::string rehearsedText_;  // the text result_ rehearsed
  bool planPinned_ = false;    // plan_ started from pinned_, not the robot
  bool terrainEditedSince_ = false;
};

}  // namespace sp
