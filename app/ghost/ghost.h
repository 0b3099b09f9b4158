#pragma once
// The predictive ghost: the console's own twin of the robot, re-anchored to
// telemetry and run ahead over the link's delay, so the operator sees the
// robot as it will be when a command sent now arrives (not as it was a round
// trip ago), and the path it takes under the commands sent (the trail).
//
// Time. Telemetry carries robot time T. The console estimates the robot's
// clock as   robot_now(w) = w + offset,  offset = max over the last 2 s of
// (T - arrival wall time) (the least-delayed frame bounds it best, as NTP's
// filters do), and the ghost shows robot time
//     ghost(w) = w + offset + round trip
// (the robot's now plus the uplink's one-way delay). A command sent at wall
// time s is taken to arrive at robot time ghost(s). The robot is assumed to
// run at real time.
//
// The pieces, each tested on its own: the clock estimate (ghost_clock.h),
// the commands in flight (in_flight.h), when to hold joints rigid
// (hold_policy.h) and what was shown against what came (prediction_record.h);
// every World steps through sim::Runner.
//
// Three threads, each owning one World built from the same model with the
// ghost's profile (ghost.step, ghost.iterations; sensors off). The
// ghost.hold joints (the upper body, the legs' hips and knees; the wheels
// and the articulation keep turning) are welded where telemetry reports
// them (sim/rigid.h: fewer bodies and rows, 2-3x faster, and a coarse step
// stays accurate over bumps, docs/performance.md) while the robot keeps them
// still and nothing sent moves them; a gait, a joint command in flight or
// the joints moving switch the ghost to the full robot, and holding resumes
// (welded anew) once they have been still for 1 s. Held links are drawn as
// telemetry reports them.
//   anchor   on the newest telemetry (at most ghost.anchor_rate per second):
//            the commands in effect by then, the frame's state through
//            linkMotions + World::setRobotMotion, then run to ghost(now)
//            applying the commands still in flight at their arrival times;
//            publishes that state (a Snapshot) as the new base;
//   present  every frame (16 ms) and at once on a new command or base: from
//            the base, advance to ghost(now), applying commands as they fall
//            due; publishes the view (what the 3D view draws) and remembers
//            what it showed for which robot time;
//   trail    from the present state, ghost.horizon seconds ahead under the
//            commands sent: base positions every 0.1 s (restarted at once
//            when a command is sent; otherwise a new one from the newest
//            state when the last is done, at most 4 times a second).
// A keypress thus reaches the view within a frame however long the round
// trip, while re-anchoring (which re-runs the whole round trip) goes on
// beside it. The anchor and trail threads run at nice 10: best effort,
// never at the expense of the robot's twin or the window's frames.
//
// Error. Each telemetry frame is compared with what the present thread
// showed for that frame's robot time: horizontal distance and yaw
// difference (anchor() returns it; errorMedian() over 10 s of robot time).
//
// How sure it is (ghost_region.h). Each state shown gets an error scale
// from its horizon, its speed, the commands that took effect within it and
// their arrival's uncertainty (the link's measured jitter, the
// calibration's delay deviation), the calibration's speed and curvature
// deviations and the terrain's height uncertainty (setErrorModel()); the
// view carries its inner and outer regions (ghost.region.inner, .outer:
// radius = the conformal layer's multiplier x scale) and the trail a band
// of the outer region at each point. Each judged frame feeds the layer and
// the departure watch: telemetry outside the ghost.region.departure region
// for ghost.region.hold s is a departure (departures(); the frame's
// GhostError says when one begins and ends), and so is a wheel that stands
// off the map's ground by more than its own layer's departure region
// (groundDiscrepancy(): the twin's wheels' clearance over the map against
// telemetry's). Frames of a run outside and of a departure stay out of the
// layers' quantiles (the region must not grow to swallow a ridge the map
// lacks) unless the departure lasts kLasting s: then it is the robot that
// differs, and the position's layer learns it (the ground's never does).
//
// Latches: while a frame reports an e-stop or failsafe, the robot is held
// still; the ghost stops the robot too and ignores the commands in flight
// (the robot refuses commands while latched).
//
// Stages. Each stage publishes its newest output in a slot of its own
// (ghost_slots.h) and rings the next stage's doorbell: anchor() the frame,
// the anchor thread the base, the present thread the view and the trail
// request, the trail thread the trail. A stage takes the newest when it is
// ready; nothing is queued, and no lock is held while computing or while
// taking another. The link's timeline (the clock estimate, the commands in
// flight, resets), the prediction record, the view and the counters each
// have their own short lock.
//
// Thread: anchor() from one thread (the link's worker, through
// app/console/telemetry_tap.h), commandSent(), view(), errorMedian() and
// the rest from one other (the console's GUI thread). The three workers
// are internal.

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/state/ghost_view.h"
#include "app/state/robot_frame.h"
#include "app/ghost/ghost_clock.h"
#include "app/ghost/ghost_region.h"
#include "app/ghost/ghost_slots.h"
#include "app/ghost/in_flight.h"
#include "app/ghost/prediction_record.h"
#include "sim/command.h"
#include "sim/params.h"
#include "sim/rigid.h"
#include "sim/robot_model.h"
#include "sim/world.h"

namespace sp {

/// Counters, for the status bar and benchmarks.
struct GhostStats {
  int64_t anchors = 0;        ///< re-anchorings done
  double anchorMs = 0;        ///< wall time of the last one (its run ahead included)
  double anchorSpan = 0;      ///< [s] robot time it ran over
  int64_t trails = 0;         ///< trails completed
  double trailMs = 0;         ///< wall time of the last one
  int64_t views = 0;          ///< views published
  int64_t twins = 0;          ///< worlds built for a new weld or a switch between held and full
  bool held = false;          ///< the newest is held (ghost.hold joints welded)
};

class Ghost {
 public:
  struct Options {
    bool runAhead = true;        ///< false: show the newest telemetry's time (no prediction; a control)
    bool inFlight = true;        ///< false: ignore commands not yet in effect at the robot (a control)
    double frameInterval = 0.016;  ///< [s] present thread's period
    double trailSpacing = 0.1;   ///< [s] robot time between trail points
    /// [s] the ghost runs at most this far ahead of the newest telemetry,
    /// whatever the clock estimate says (a robot whose time leaps, a round
    /// trip of hours): beyond it the view says so instead of predicting.
    double maxAhead = 10;
    /// false: the regions take the Gaussian multipliers of the scale alone
    /// (the conformal layer off; a control).
    bool conformal = true;
    /// false: the scale is the floor alone (the estimate's deviations, the
    /// link's jitter and the terrain's uncertainty taken as zero; a control).
    bool sources = true;
    /// Every deviation of the error model (the floor's too) multiplied by
    /// this: a model wrong by a factor, which the conformal layer must
    /// correct and the Gaussian multipliers cannot (a control).
    double modelFactor = 1;
  };

  /// The ghost's physics profile of `params`: ghost.step and
  /// ghost.iterations as its step and solver iterations (the twin the
  /// console's calibration fits, too).
  static SimParams profile(const SimParams& params);
  /// Builds the three worlds from `world`, calibrated by `params`'
  /// calibration.* keys (commands act calibration.delay after they
  /// arrive), with the ghost profile of `params`, and starts the threads.
  /// nullptr and `error` if a world cannot be built or the world has no robot.
  static std::unique_ptr<Ghost> create(const WorldModel& world, const SimParams& params, std::string& error);
  static std::unique_ptr<Ghost> create(const WorldModel& world, const SimParams& params, const Options& options,
                                       std::string& error);
  /// Stops and joins the threads.
  ~Ghost();
  Ghost(const Ghost&) = delete;
  Ghost& operator=(const Ghost&) = delete;

  /// A telemetry frame arrived now (joints in the model's order), with the
  /// link's round trip [s]. Returns the frame against what the ghost showed
  /// for its time, when it showed something then.
  std::optional<GhostError> anchor(const RobotFrame& frame, double roundTrip);
  /// The operator sent `command` now; it is taken to arrive at ghost(now).
  void commandSent(const Command& command);
  /// The robot as calibrated (app/calibration): `world` (the files'
  /// calibratedWorld()) is what the ghost's twins are built from from the
  /// next re-anchoring on (its step boundary), and commands sent from now
  /// on act `delay` seconds after they arrive.
  void setCalibration(WorldModel world, double delay);
  /// Commands sent so far (commandSent() calls).
  uint64_t commandsSent() const;
  /// The ghost as it is now (a copy).
  GhostView view() const;
  /// The view's version, cheaper than view() to poll.
  int64_t viewVersion() const;
  /// Median of the position and heading errors over the last 10 s of robot
  /// time; nullopt before the first comparison.
  std::optional<std::pair<double, double>> errorMedian() const;
  /// [m] the largest position error over the same 10 s.
  std::optional<double> errorWorst() const;
  /// What the region's scale is built from besides the link's jitter
  /// (measured): the calibration's deviations and the terrain's
  /// uncertainty (ghost_region.h). From the next view on.
  void setErrorModel(const ErrorModel& model);
  /// The model last given (before Options' controls act on it).
  ErrorModel errorModel() const;
  /// The departures telemetry showed since the last reset, oldest first
  /// (the last may still be on: ended < 0).
  std::vector<Departure> departures() const;
  /// How many departures began since the last reset (cheap to poll).
  size_t departureCount() const;
  /// The departure on now, if one is.
  std::optional<Departure> departing() const;
  /// The share of judged frames inside the inner, outer and departure
  /// regions (as each stood when the frame came), and how many were judged.
  struct Coverage {
    std::array<double, 3> share{};
    size_t judged = 0;
  };
  Coverage coverage() const;
  /// [s] a departure lasting this long is the robot, not a place: the
  /// conformal layer learns from it from then on.
  static constexpr double kLasting = 5;

  /// The robot reported its twin diverged (`why`): the ghost stops
  /// predicting (its view keeps the last prediction, with `why` as its
  /// problem) until the next anchor().
  void halt(const std::string& why);
  GhostStats stats() const;
  /// Robot time the ghost shows at wall time `wall` (steady clock [s]).
  double ghostTime(double wall) const;
  /// The steady clock the ghost reads [s].
  static double now();

 private:
  struct Base;  // a published anchored state
  struct TrailRequest;
  struct AnchorRun;
  struct AnchorInput;
  /// What the ghost's worlds are built from: the world with its robot's
  /// ghost.hold joints welded at the pose of the first telemetry (or the
  /// full robot without any).
  struct Twin {
    WorldModel world;
    std::optional<RigidRobot> rigid;
    std::vector<int> held;  ///< the full robot's joints welded
  };

  Ghost(const WorldModel& world, const SimParams& params, const Options& options);
  /// The twin welded at `positions` (the full robot's joints), or the full
  /// robot when not `hold`. Null and `error` when the hold cannot be made.
  std::shared_ptr<const Twin> makeTwin(const std::vector<double>& positions, bool hold, std::string& error) const;
  /// Gives `to` (just built) the controller set-points of `from` (the twin
  /// it replaces), actuator by name; a joint `from` held holds where
  /// `positions` (the full robot's) has it.
  void carryControl(const World& from, const Twin& fromTwin, World& to, const Twin& toTwin,
                    const std::vector<double>& positions) const;
  std::unique_ptr<World> buildWorld(const Twin& twin, std::string* error = nullptr) const;
  /// A state of `twin`'s robot as the full robot's joint positions: held
  /// ones as `reported` has them (the newest telemetry), when it has them.
  std::vector<double> fullPositions(const Twin& twin, const std::vector<double>& joints,
                                    const std::vector<double>* reported) const;
  /// Runs `loop` on the calling thread until it returns; restarts it when it throws.
  void guarded(const char* name, void (Ghost::*loop)());
  void anchorLoop();
  // The anchor loop's parts: the next frame and the commands around it
  // (false: the ghost ends); the twin rebuilt for a new weld or
  // calibration; the frame's state set, with the commands in effect. Each
  // "" or the problem the view shows.
  bool takeAnchorInput(AnchorRun& run, AnchorInput& in);
  std::string rebuildTwin(AnchorRun& run, const RobotFrame& frame, bool hold);
  std::string setAnchorState(AnchorRun& run, AnchorInput& in, bool latched);
  void presentLoop();
  void trailLoop();
  /// Steps `world` (through sim::Runner) from robot time `t` to `target`,
  /// submitting commands[next...] at the first step boundary at or after
  /// their times, as the robot does; `abort` is asked every 64 steps.
  /// False if the world diverged or was aborted.
  bool advance(World& world, double& t, double target, const std::vector<SentCommand>& commands, size_t& next,
               const std::function<bool()>& abort = {}) const;
  void setProblem(const std::string& problem);
  /// `e` (a frame just compared) given its regions, judged for a
  /// departure and fed to the conformal layer (recordMutex_ held).
  void judge(GhostError& e, const RobotFrame& frame);
  /// What the error scale of a state shown at robot time `t` from
  /// telemetry of `made`, at base speed `speed`, is made of (`timeline` and
  /// `spread` from the link's timeline).
  ErrorSources sourcesOf(double t, double made, double speed, const std::vector<std::pair<double, Command>>& timeline,
                         double spread) const;
  /// A judged frame into the layers (recordMutex_ held).
  struct Judged;
  void learn(const Judged& judged);
  /// `model` as the options have it: the sources dropped, the factor applied.
  ErrorModel asOptioned(ErrorModel model) const;
  /// The destructor asked the threads to end (a long run ahead gives up).
  bool stopping() const { return stop_.load(); }

  WorldModel model_;  // the full world, as calibrated: the anchor thread's once it runs
  const RobotModel robot_;  // the full robot as the files have it: its wheels' clearances
  SimParams params_;  // the ghost profile
  Options options_;
  std::vector<int> held_;  // joints the ghost may hold rigid (ghost.hold's subtrees but the drive's), sorted
  std::atomic<bool> stop_{false};

  // Each stage's newest output, taken by the next when it is ready
  // (ghost_slots.h), and each thread's doorbell.
  ghost_detail::Slot<RobotFrame> frames_;               // anchor() -> anchor thread (and the held joints drawn)
  ghost_detail::Slot<Base> bases_;                      // anchor thread -> present thread
  ghost_detail::Slot<TrailRequest> trailRequests_;      // present thread -> trail thread
  ghost_detail::Doorbell anchorBell_, presentBell_, trailBell_;

  // The link's timeline: the robot's clock estimate, the commands in
  // flight and the robot's resets, which every stage reads together.
  mutable std::mutex timelineMutex_;
  GhostClock clock_;
  InFlightCommands commands_;  // the last 10 s of robot time
  uint64_t epoch_ = 0;  // counts robot resets (its clock went back)
  double delay_ = 0;  // [s] calibration.delay: commands act this long after they arrive

  mutable std::mutex calibrationMutex_;
  std::optional<WorldModel> nextModel_;  // a calibration for the anchor thread to take

  mutable std::mutex recordMutex_;
  PredictionRecord record_;  // what was shown against what came
  ErrorModel errorModel_;    // the region's sources besides the link, as optioned
  ErrorModel givenModel_;    // ... as given
  ConformalLayer region_;    // inner, outer, departure
  ConformalLayer vertical_;  // the departure's level, over the vertical pose's scores
  DepartureWatch watch_;
  std::vector<Departure> departures_;
  // The map telemetry's wheels are judged on, with the terrain edits sent
  // (each from the robot time it takes effect).
  TerrainSpec ground_;
  std::deque<std::pair<double, TerrainPatchCmd>> groundEdits_;
  // A judged frame as the layers learn it: its errors and what its scale
  // was made of, so that a new model rescores the window.
  struct Judged {
    double time, position, vertical;
    ErrorSources sources;
    bool ground;  // the ground's layer learns it too (no departure on)
  };
  std::deque<Judged> learnt_;        // the layers' window, with its sources
  std::vector<Judged> pending_;      // frames outside, kept from the layers until judged no departure

  mutable std::mutex viewMutex_;  // what the GUI copies out
  GhostView view_;
  std::string halted_;  // why the ghost does not predict (halt()); "" while it does

  mutable std::mutex statsMutex_;
  GhostStats stats_;

  std::thread anchorThread_, presentThread_, trailThread_;
};

}  // namespace sp
