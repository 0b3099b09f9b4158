#pragma once
// The console's fourth job: editing the terrain heightfield (issue 16). The
// panel holds the brush (raise, lower, smooth, flatten to a picked height,
// noise; radius, strength) and the editor (app/console/terrain_editor.h: strokes
// with undo and redo); the 3D view paints with it (SceneView's edit mode)
// and MainWindow sends each patch to the view, the console's twin and, when
// it announces `terrain_edit`, the robot's twin. New, Import and Save write
// a terrain file and the world file that uses it (sim/terrain_file.h).
//
// Thread: GUI thread.

#include <QString>
#include <QWidget>

#include <functional>
#include <memory>
#include <optional>

#include "app/console/terrain_editor.h"
#include "app/console/terrain_limits.h"
#include "sim/robot_model.h"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QPushButton;

namespace sp {

class TerrainPanel : public QWidget {
  Q_OBJECT

 public:
  explicit TerrainPanel(QWidget* parent = nullptr);
  ~TerrainPanel() override;

  /// The world whose terrain is edited (its file is the base of saved
  /// worlds) and the console's editor of its heights (null on a plane,
  /// which cannot be edited: the panel says so); both must outlive their
  /// use here (the next setTerrain()). The panel keeps no heights of its own.
  void setTerrain(const WorldModel* world, TerrainEditor* editor);
  bool editable() const { return editor_ != nullptr; }
  const TerrainEditor* editor() const { return editor_; }

  void setBrush(const Brush& brush);
  Brush brush() const;
  /// Edit mode (the view paints with the left button).
  void setEditing(bool on);
  bool editing() const;

  /// A dab at world point `ground` (from the view): a patch follows when it
  /// changed heights. Dabs closer than a quarter of the radius to the last
  /// one of the stroke are skipped, so strength is per distance painted,
  /// not per mouse event.
  void dabAt(const Vec3& ground);
  /// The cursor over world point `ground` (from the view): the panel shows
  /// the ground's height there, what the open stroke has added, what the
  /// next dab would add, and warns (riskChanged) when that dab would make a
  /// rise the robot cannot drive (app/console/terrain_limits.h).
  void hoverAt(const Vec3& ground);
  /// The warning shown, "" when none.
  QString riskText() const;
  /// The preview line ("Here: ground 0.23 m; this stroke +0.10 m; a dab +0.05 m").
  QString previewText() const;
  void endStroke();
  void undo();
  void redo();
  /// Flatten's target from a picked ground point (terrain heights).
  void setFlattenHeight(double height);

  /// Saves the edited grid to `terrainFile` (.asc, .pgm, .csv) and the world
  /// file using it to `worldFile`; "" or why not.
  QString save(const QString& terrainFile, const QString& worldFile);
  /// A flat new terrain (`width` x `depth` m, `resolution` m, at
  /// `baseHeight`) saved as `terrainFile` with its world `worldFile` (the
  /// current world's, with this terrain); "" or why not. Open it to use it.
  QString createNew(double width, double depth, double resolution, double baseHeight, const QString& terrainFile,
                    const QString& worldFile);
  /// A grid file (.asc, .pgm, .csv) or a 1-D profile (distance,height
  /// lines, extruded over `depth` at `resolution`), saved as above; "" or why.
  QString import(const QString& source, bool profile, double width, double depth, double resolution,
                 const QString& terrainFile, const QString& worldFile);
  /// Where the edits go, for the operator ("the stand-in and the console's
  /// twin", "the console's twin only: ...").
  void setReach(const QString& text);

 signals:
  /// Apply this edit: to the view, the console's twin, the robot's twin.
  void patch(const sp::TerrainPatchCmd& patch);
  void strokeEnded();
  void editingChanged(bool on);
  void brushRadiusChanged(double radius);
  /// The next dab (hovered) or the last one (painted) makes a rise the
  /// robot cannot drive, or no longer does.
  void riskChanged(bool risky);
  /// Pick flatten's height: the next click on the ground.
  void pickRequested();
  /// A world file written by New or Import, to open.
  void openWorldRequested(const QString& worldFile);

 private:
  void updateState();
  /// Shows `risk` (or clears it); `made`: the stroke has made it, else the next dab would.
  void showRisk(const std::optional<TerrainRisk>& risk, bool made);
  void askNew();
  void askImport();
  void askSave();
  /// Asks where to save, writes with `write(terrainFile, worldFile)` and
  /// asks to open the world written (or says why it failed).
  void writeAndOpen(const QString& title, const std::function<QString(const QString&, const QString&)>& write);

  const WorldModel* world_ = nullptr;
  TerrainEditor* editor_ = nullptr;
  std::optional<Vec2> lastDab_;
  std::optional<DrivableLimits> limits_;
  double wheelRadius_ = 0;
  bool risky_ = false;
  QPushButton* editButton_ = nullptr;
  QComboBox* kind_ = nullptr;
  QDoubleSpinBox* radius_ = nullptr;
  QDoubleSpinBox* strength_ = nullptr;
  QDoubleSpinBox* flatten_ = nullptr;
  QPushButton* pick_ = nullptr;
  QPushButton* undo_ = nullptr;
  QPushButton* redo_ = nullptr;
  QPushButton* save_ = nullptr;
  QLabel* state_ = nullptr;
  QLabel* preview_ = nullptr;
  QLabel* risk_ = nullptr;
  QLabel* reach_ = nullptr;
  uint32_t seed_ = 1;
};

}  // namespace sp
