#pragma once
// How far to trust the ghost: a region around each prediction that holds
// the robot with a stated probability, and a watch that says when the robot
// leaves it (it departs from its twin: the ground or the robot differ from
// the files there).
//
// Method (docs/architecture.md, "How sure the ghost is"). Each prediction
// gets a scale sigma [m]: what its sources of error (the calibration's
// deviations, the link's jitter and the commands' arrival, the terrain's
// height uncertainty, the twin's floor) would move the base by over its
// horizon, propagated to first order through the kinematics of a rolling,
// articulated robot (errorScale). Its region at level p is the disc of
// radius  q_p * sigma,  where q_p comes from an online conformal layer
// (ConformalLayer): the p-quantile of the scores  error / sigma  of the
// predictions telemetry has judged over the last `window` seconds,
// corrected by adaptive conformal inference (Gibbs and Candes 2021: the
// level the quantile is taken at moves by gamma each judged prediction,
// up after a miss and down after a hit), so that the share of predictions
// the region holds is p over any long run however wrong sigma's model is,
// and comes back to p after the robot changes. sigma only shapes the
// region (wide when turning at speed, after a command whose arrival is
// uncertain, narrow when standing); the layer makes it true.
//
// Why not an ensemble of twins: the ghost's twin already takes one of the
// two cores at 10 re-anchorings a second; k twins drawn from the estimate
// cost k times that, and they would still miss what no parameter holds
// (the terrain, the commands' arrival), which the conformal layer must
// cover anyway. Rehearsals, which have time, draw twins from the estimate
// (app/rehearse/).
//
// Thread: plain values; the ghost guards them (its record's mutex).

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sim/command.h"
#include "sim/math.h"
#include "sim/robot_model.h"

namespace sp {

/// What one prediction's error comes from.
struct ErrorSources {
  double horizon = 0;  ///< [s] robot time from the telemetry it ran from to the time shown
  double speed = 0;    ///< [m/s] the base's horizontal speed at the time shown
  /// [m/s] how fast the shown base moves per second its commands' arrival
  /// is off: over the commands that took effect within the horizon, the
  /// change of speed they made, plus the sideways drift a change of
  /// articulation makes until the time shown (speed * dphi * age / L).
  double timing = 0;
  /// [s] the link's jitter when it was shown (GhostClock::spread): a
  /// command's arrival is off by it as well as by the model's `arrival`.
  double spread = 0;
};

/// The uncertainties the scale is built from.
struct ErrorModel {
  double floor = 0.004;       ///< [m] telemetry's and the twin's own resolution (a robot standing still)
  double speed = 0.01;        ///< relative deviation of the speed (the calibration's radius and motor gain)
  double curvature = 0.005;   ///< [1/m] deviation of the path's curvature (the tyres' side split)
  double arrival = 0.02;      ///< [s] deviation of a command's arrival (the link's jitter, the delay's deviation)
  double terrain = 0.01;      ///< [m] the ground's height deviation (the world's terrain uncertainty)
  double height = 0.8;        ///< [m] the base's height above the ground: a tilt moves it sideways by this
  double wheelbase = 1.1;     ///< [m] front to rear wheels: a height error over it tilts the base
  double track = 0.84;        ///< [m] left to right wheels: a side split of the tyres curves the path
  friend bool operator==(const ErrorModel&, const ErrorModel&) = default;
};

/// The model's geometry for `world`'s first robot (its drive's wheels, its
/// base's height above them) and its terrain's uncertainty
/// (terrainUncertainty()), with the defaults' deviations.
ErrorModel errorModelFor(const WorldModel& world);

/// The scale [m] of a prediction's horizontal error (one standard
/// deviation per axis were it Gaussian): the root sum of squares of
///   floor, speed * horizon * speed deviation (along the path),
///   curvature * (speed * horizon)^2 / 2 (across it),
///   timing * hypot(arrival deviation, spread) (the commands' arrival),
///   terrain * height / wheelbase (the base tilted by ground the map has wrong).
double errorScale(const ErrorSources& sources, const ErrorModel& model);

/// ErrorSources::timing for a state shown at robot time `shown` from
/// telemetry of robot time `made`, at base speed `speed`: `commands` are
/// those sent, each with the robot time it takes effect, oldest first
/// (those before `made` give the set-point the first one changed).
/// Drives and stops count; a gait or a joint command counts as a change of
/// `speed` (its effect on the base is not modelled: the layer covers it).
double commandTiming(const std::vector<std::pair<double, Command>>& commands, double made, double shown, double speed,
                     double wheelbase);

/// The scale [m] of the ground's discrepancy under the wheels
/// (groundDiscrepancy()): the floor's (the tyres' compression, the
/// interpolation of the map), the terrain's uncertainty, and a little of
/// the prediction's horizontal scale `horizontal` [m] (a wheel predicted
/// on other ground than it stands on: 2 %, a grid cell's curvature).
double verticalScale(double horizontal, const ErrorModel& model);

/// [m] each drive wheel's clearance over the map's ground (FL, FR, RL, RR): its
/// hub's distance from the ground along the ground's normal, less the
/// wheel's radius: about 0 for a wheel on the ground, below 0 for one lower
/// than the map has the ground (a hollow the map lacks), above for one lifted
/// (a step the map lacks, or a gait). NaN for a robot without a drive. Of
/// the robot `robot` at `base` with `jointPositions` (model order).
/// `ground(x, y)` is the map's height there (a World's terrainHeight, or
/// groundHeight() of a TerrainSpec).
using WheelClearances = std::array<double, 4>;
constexpr double kNoClearance = std::numeric_limits<double>::quiet_NaN();
/// `hubs`: where each wheel's hub is (when given).
WheelClearances wheelClearances(const RobotModel& robot, const std::function<double(double, double)>& ground,
                                const Pose& base, std::span<const double> jointPositions,
                                std::array<Vec3, 4>* hubs = nullptr);

/// [m] how far telemetry's ground is from the map's under the wheels: the
/// largest |actual - predicted| clearance over the wheels the twin had on
/// the ground (predicted below kLiftedClearance; a wheel it lifted, as a
/// gait does, is left out). The prediction's horizontal error hardly enters:
/// both clearances are measured from the map where each robot stands. 0
/// when no wheel can be compared.
/// `worst`: the wheel it is of (-1: none).
double groundDiscrepancy(const WheelClearances& predicted, const WheelClearances& actual, int* worst = nullptr);
constexpr double kLiftedClearance = 0.02;  ///< [m]
/// [m] a ground discrepancy this large is never what the map's own error
/// gives (under 5 mm on mapped ground, bench_region): the ground's layer
/// never learns it, even from a run outside too short to be a departure.
/// (Learnt, the runs of a rear wheel dipping in and out at a hollow's
/// edge lifted the 99 % limit from 4 mm to 63 mm for the rest of the run,
/// and half the crossings went unseen: bench_region --departures 20.)
constexpr double kUnlearntGround = 0.02;
/// [N] a wheel telemetry reports carrying less is not on the ground (a
/// WorkPartner wheel carries about 500 N standing).
constexpr double kLoadedWheel = 50;

/// The region's multiplier at `level` for a scale that is a 2-D Gaussian's
/// per-axis deviation: sqrt(-2 ln(1 - level)) (Rayleigh). What the layer
/// uses before it has judged enough predictions.
double gaussianMultiplier(double level);

/// The online conformal layer: scores in, the multiplier of each level out.
class ConformalLayer {
 public:
  struct Options {
    std::vector<double> levels = {0.5, 0.9, 0.99};  ///< each in (0, 1)
    double window = 20;  ///< [s] of robot time the quantiles are over
    int minScores = 50;  ///< below this many, gaussianMultiplier()
    /// Adaptive conformal inference's step per judged prediction (0: off,
    /// the window's plain quantile), for levels up to 90 %; a level p above
    /// takes 10 (1 - p) of it. At 50 judged predictions a second, 0.005
    /// moves a level by 0.25 a second at most.
    double gamma = 0.005;
  };
  explicit ConformalLayer(Options options);
  ConformalLayer() : ConformalLayer(Options{}) {}

  /// A judged prediction at robot time `time`: its error over its scale
  /// (judge(), then learn()).
  void add(double time, double score) {
    judge(score);
    learn(time, score);
  }
  /// Counts a judged prediction for the coverage figures, against the
  /// regions as they stand.
  void judge(double score);
  /// The window's scores recomputed (the scale's model changed: the old
  /// scores meant another scale): `rescore` maps each (time, score) to its
  /// new score. The levels stay where they are.
  template <typename F>
  void rescore(F rescore) {
    for (Score& s : window_) s.score = rescore(s.time, s.score);
    update();
  }
  /// Learns from it: the levels move (adaptive conformal inference) and it
  /// joins the window. A departure's frames are judged, not learnt: the
  /// robot is not on the ground the twin knows there.
  void learn(double time, double score);
  /// The multiplier of `levels[i]`: the region at that level is q * sigma.
  double multiplier(size_t i) const { return multipliers_.at(i); }
  /// The multiplier at levels[i], by level (the nearest one).
  double multiplierAt(double level) const;
  const std::vector<double>& levels() const { return options_.levels; }
  /// Of the predictions judged so far, the share inside levels[i]'s region
  /// as it stood when each came (the layer's own coverage); nullopt before one.
  std::optional<double> coverage(size_t i) const;
  size_t judged() const { return judged_; }
  size_t scores() const { return window_.size(); }
  void clear();

  /// "" or what is wrong with `levels` (each in (0, 1), ascending).
  static std::string checkLevels(const std::vector<double>& levels);

 private:
  void update();  // multipliers_ from window_ and alpha_
  Options options_;
  struct Score {
    double time, score;
  };
  std::deque<Score> window_;
  std::vector<double> alpha_;        // per level: the quantile level the layer takes now
  std::vector<double> multipliers_;  // per level
  std::vector<size_t> hits_;
  size_t judged_ = 0;
};

/// A departure: telemetry outside the 99 % region for `hold` seconds: the
/// base's position outside its disc, or its vertical pose outside its own
/// region: the ground under a wheel not where the map has it (a layer of
/// its own over groundDiscrepancy()'s scores).
struct Departure {
  double time = 0;   ///< [s] robot time it began (the first frame outside)
  /// Where: the robot's base then (as telemetry reported it), or for one
  /// under the wheels (the position inside its region) the wheel that
  /// stood off the map's ground: the place the ground differs.
  Vec3 where;
  double error = 0;  ///< [m] the largest distance from the ghost's prediction while it lasts
  double vertical = 0;  ///< [m] the largest ground discrepancy under a wheel (groundDiscrepancy()) while it lasts
  double ended = -1; ///< [s] robot time it cleared (< 0: still on)
  /// The ground under a wheel was off the map's in it: a place differs.
  /// Without, the wheels stood on the map's ground and the base went
  /// elsewhere than its twin: the robot differs (what calibration fits).
  bool ground = false;
  /// For the operator: "the robot departs from its twin by 28 cm at
  /// (5.1, 0.2): the ground or the robot differ from the files there".
  std::string describe() const;
};

/// Watches judged predictions for departures.
class DepartureWatch {
 public:
  struct Options {
    double hold = 0.5;      ///< [s] outside this long, every frame: a departure
    /// [s] a run outside survives frames inside for up to this long: a
    /// wheel unloaded for a frame at a hollow's edge leaves the judging
    /// (kLoadedWheel), and the one frame it did split 0.67 s outside into
    /// runs of 0.37 and 0.26 s, none a departure (bench_region
    /// --departures 32: a crossing announced 2.7 s late, by the rear axle).
    double gap = 0.1;
    double clear = 0.5;     ///< [s] inside this long: it clears
    /// [m] an error below this is never a departure, whatever the region
    /// (a region of millimetres on a robot standing still).
    double minimum = 0.03;
    /// [m] the same for the vertical discrepancy: a 5 cm step under one
    /// axle makes 2.5 cm; on mapped ground it stays below 5 mm
    /// (bench_region's false alarms).
    double minimumVertical = 0.01;
  };
  /// What one judged frame changed.
  enum class Change { None, Began, Ended };

  explicit DepartureWatch(Options options) : options_(options) {}
  DepartureWatch() : DepartureWatch(Options{}) {}

  /// A frame at robot time `time` at `where` was `error` from its
  /// prediction, whose departure region had radius `radius`, and
  /// `vertical` off in its vertical pose, whose region was `verticalLimit`.
  /// `wheel`: where the wheel that stood furthest off the map was (a
  /// departure under the wheels is placed there).
  Change judge(double time, const Vec3& where, double error, double radius, double vertical = 0,
               double verticalLimit = 1e300, const std::optional<Vec3>& wheel = std::nullopt);
  /// The departure on now, or the last one (ended >= 0); nullopt before any.
  const std::optional<Departure>& last() const { return last_; }
  bool departing() const { return last_ && last_->ended < 0; }
  /// A frame is outside, or the departure is on: the conformal layer
  /// leaves it out.
  bool suspect() const { return outsideSince_ >= 0 || departing(); }
  int count() const { return count_; }
  void clear();

 private:
  Options options_;
  double outsideSince_ = -1;  // robot time of the first frame of a run outside
  double outsideLast_ = -1;   // ... and of its last frame outside
  Vec3 outsideWhere_;
  double outsideWorst_ = 0, outsideVertical_ = 0;
  bool outsideGround_ = false;
  double insideSince_ = -1;   // while departing: the first frame of a run inside
  std::optional<Departure> last_;
  int count_ = 0;
};

}  // namespace sp
