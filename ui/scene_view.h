#pragma once
// The console's 3D view: the world (terrain, objects, a 1 m ground grid, axes
// at the origin), the robot and the dynamic objects as telemetry reports them
// (base pose + joint positions through sp::linkPoses; object poses by name)
// and the latest laser scan, drawn with OpenSceneGraph inside a QOpenGLWidget.
//
// OSG is built for fixed-function GL 2: the application must set a default
// QSurfaceFormat of OpenGL 2.1 CompatibilityProfile before creating its
// QApplication (shared/STACK.md). QT_QPA_PLATFORM=offscreen cannot draw it;
// headless runs use xvfb-run.

#include <QOpenGLWidget>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/command.h"
#include "sim/math.h"
#include "sim/robot_model.h"

namespace sp {

/// Where a world object is, by its name in the world file.
struct NamedPose {
  std::string name;
  Pose pose;  ///< in the world frame [m]
};

/// An orbit-camera 3D view of one world and its first robot.
///
/// Setters only store state and mark it dirty; a 16 ms QTimer schedules a
/// repaint, and the scene graph is brought up to date in paintGL, so setters
/// are cheap enough for telemetry rates.
///
/// Mouse: left drag orbits, the wheel zooms, right or middle drag pans (which
/// turns follow mode off).
///
/// Thread: GUI thread only, like every QWidget. The view must stay in its
/// top-level window: moving it to another one recreates Qt's GL context,
/// which this view does not rebuild its GL objects for.
/// Debian's OpenSceneGraph is a fixed-function GL 2 build: it needs a GL 2.1
/// compatibility context. Sets it as the default surface format; call
/// before the QApplication exists (the console, the GUI tests, benchmarks).
void setSceneSurfaceFormat();

class SceneView : public QOpenGLWidget {
  Q_OBJECT

 public:
  explicit SceneView(QWidget* parent = nullptr);
  ~SceneView() override;

  /// The ghost's tint (red, green, blue, alpha): one colour over its whole
  /// silhouette, the scene behind it blended in once.
  static constexpr float kGhostTint[4] = {0.15f, 0.55f, 1.00f, 0.55f};

  /// Builds the scene from `world` (copied; the view keeps what it needs):
  /// the terrain (a plane as a large quad, a heightfield as a lit mesh
  /// coloured by height), the objects at their initial poses, the ground grid
  /// and axes, and robots[0]'s links at its initial pose with zero joints.
  /// Replaces any previous world and laser scan; the camera keeps its angles
  /// and distance. A world without robots shows no robot and no laser.
  void setWorld(const WorldModel& world);

  /// Places the robot: `base` is link 0's pose in the world, `jointPositions`
  /// one value per joint in robot.joints order ([rad] or [m]; missing values
  /// count as zero). Cheap: the link transforms are updated on the next paint.
  void setRobotState(const Pose& base, const std::vector<double>& jointPositions);

  /// A second, translucent robot (the predictive ghost, a replay cursor):
  /// the same links as the robot, tinted light blue and see-through, placed
  /// as setRobotState() places the robot. Hidden until setGhostVisible(true);
  /// setWorld() puts it at the robot's initial pose.
  void setGhostState(const Pose& base, const std::vector<double>& jointPositions);
  void setGhostVisible(bool visible);
  bool ghostVisible() const;
  /// The ghost's predicted path: a line through `points` (world frame),
  /// shown while the ghost is.
  void setGhostTrail(const std::vector<Vec3>& points);
  /// Points of the trail drawn in the last frame (0 while hidden).
  size_t drawnTrailPoints() const;
  /// How sure the ghost is (app/ghost/ghost_region.h), drawn with it: its
  /// inner and outer regions about its base, discs [m] on the ground (0:
  /// none), and the trail's band, the outer region's radius at each point
  /// of setGhostTrail()'s (empty: no band).
  void setGhostRegion(double inner, double outer);
  void setGhostTrailBand(const std::vector<double>& radii);
  /// The outer disc's radius and the band's points drawn in the last frame
  /// (0 while hidden).
  double drawnGhostRegion() const;
  size_t drawnTrailBand() const;
  /// [m] how far ahead and behind the ghost its faint spread is drawn (the
  /// outer region's radius; 0 when hidden: the ghost or region hidden, or
  /// the region under 5 cm).
  double drawnGhostSpread() const;
  /// Where the robot departed from its twin (its base at each departure's
  /// start), marked on the ground in red whether the ghost is shown or not;
  /// `lastOn`: the last one is on now (drawn brighter).
  void setDepartureMarks(const std::vector<Vec3>& places, bool lastOn);
  size_t drawnDepartureMarks() const;
  /// Where the ghost's base link was drawn in the last frame; the identity
  /// while it is hidden.
  Pose drawnGhostBasePose() const;

  /// The rehearsal (ui/jobs/sequence/sequence_panel.h): a second translucent robot, amber,
  /// at the rehearsal scrubber's time, and the rehearsed path on the ground;
  /// hidden until setRehearsalVisible(true).
  void setRehearsalState(const Pose& base, const std::vector<double>& jointPositions);
  void setRehearsalPath(const std::vector<Vec3>& points);
  /// A closed line drawn with the path (the robustness runs' end positions).
  void setRehearsalEnvelope(const std::vector<Vec3>& points);
  /// The rehearsed path's band: a radius per rehearsal path point (the
  /// robustness runs' 90 %, SequenceWorkflow::band()), drawn translucent on
  /// the ground with the path; empty for none.
  void setRehearsalBand(const std::vector<double>& radii);
  /// The band's points as drawn (0 when hidden or none).
  size_t drawnRehearsalBand() const;
  void setRehearsalVisible(bool visible);
  bool rehearsalVisible() const;
  /// The amber robot itself (its path stays): hidden once the rehearsed
  /// sequence has run, shown again when scrubbed.
  void setRehearsalRobotShown(bool shown);
  bool rehearsalRobotDrawn() const;  ///< at the last frame
  size_t drawnRehearsalPathPoints() const;
  Pose drawnRehearsalBasePose() const;

  /// Places dynamic objects of the world by name (world frame). Names that
  /// are no dynamic object of the world are ignored; objects not named keep
  /// their last pose (the world file's until set). Cheap: the transforms are
  /// updated on the next paint.
  void setObjectPoses(const std::vector<NamedPose>& objects);

  /// The latest laser scan of robots[0]'s first laser sensor, drawn from the
  /// sensor's pose under the robot's current state (link pose * mounting
  /// pose). Beam k points at angleMin + k * angleStep [rad] about the
  /// sensor's z axis. Ranges in [m]: finite ones within the sensor's maxRange
  /// are hits (a beam and a point); inf or beyond maxRange (no return) draws a
  /// faint beam to maxRange; NaN (invalid) is omitted. An empty `ranges`
  /// clears the scan.
  void setLaser(double angleMin, double angleStep, const std::vector<double>& ranges);
  /// Shows or hides the laser scan (shown by default).
  void setLaserVisible(bool visible);
  bool laserVisible() const;
  /// Draws the robot grey while its data is stale (no telemetry lately):
  /// the operator must not take an old pose for the present one.
  void setStale(bool stale);
  bool stale() const;

  /// Follow mode keeps the orbit centre on the robot base (default on).
  void setFollow(bool on);
  bool follow() const;
  /// Where the camera goes. Follow: the orbit centre on the base, the angles
  /// the operator's. Chase: behind the robot, turning as it turns, 6 m off
  /// and 15° up. Top: straight down from 18 m, the robot's forward up the
  /// screen. Free: the camera stays where it is put. Orbiting (left drag)
  /// a chase or top camera makes it a follow one; panning, a free one.
  enum class Camera { Follow, Chase, Top, Free };
  void setCamera(Camera camera);
  Camera camera() const;
  /// The eye of the last frame drawn (world frame).
  Vec3 cameraEye() const;
  /// Default camera angles and distance, centred on the robot base (the
  /// origin without a robot). Follow mode is left as it is.
  void resetView();

  /// Where the base link was drawn in the last frame (world frame): the
  /// robot as the screen shows it, not as last set.
  Pose drawnBasePose() const;

  /// Frames drawn since construction.
  int64_t framesDrawn() const;
  /// Frames drawn per second over the last completed second; 0 before the
  /// first second of drawing.
  double framesPerSecond() const;

  // Terrain editing (issue 16). In edit mode the left button paints: a
  // `terrainDab` at the ground under the cursor on press and on every move,
  // `terrainStrokeEnded` on release; the brush's footprint (a ring of
  // `setBrushRadius` metres draped on the ground) follows the cursor. The
  // right and middle buttons and the wheel move the camera as always. In
  // pick mode the next left click emits `groundPicked` instead (once).
  void setTerrainEditing(bool on);
  bool terrainEditing() const;
  void setBrushRadius(double radius);
  /// The footprint ring in the warning colour (amber) instead of yellow:
  /// the next dab asks more of the robot than it can drive.
  void setBrushWarning(bool on);
  void pickGround();
  /// The ground under the view's point `pixel` (logical pixels): the first
  /// crossing of the camera ray with the terrain; nullopt when it misses.
  std::optional<Vec3> groundAt(QPointF pixel) const;
  /// Changes the drawn heightfield in place: the vertices of the patch's
  /// samples and the normals around them (no rebuild); the draped grid lines
  /// follow at the end of the stroke (finishTerrainEdit).
  void applyTerrainPatch(const TerrainPatchCmd& patch);
  void finishTerrainEdit();
  /// The drawn height of grid sample (i, j) (for tests: the mesh follows edits).
  std::optional<double> drawnTerrainHeight(int i, int j) const;

 protected:
  void initializeGL() override;
  void resizeGL(int w, int h) override;
  void paintGL() override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;

 signals:
  /// At the start of every frame, before the scene graph is brought up to
  /// date: a source that changes every frame (the ghost) sets its state in
  /// a direct connection and is drawn in this very frame.
  void frameStarting();
  void terrainDab(const sp::Vec3& ground);
  /// Edit mode: the ground under the cursor as it moves (painting or not).
  void terrainHover(const sp::Vec3& ground);
  void terrainStrokeEnded();
  void groundPicked(const sp::Vec3& ground);
  /// The camera changed preset (the operator dragged, or setCamera()).
  void cameraChanged(sp::SceneView::Camera camera);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_;
};

}  // namespace sp
