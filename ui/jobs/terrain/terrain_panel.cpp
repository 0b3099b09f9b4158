#include "ui/jobs/terrain/terrain_panel.h"

#include <QBoxLayout>
#include <QComboBox>
#include <QDialog>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QLabel>
#include <QMessageBox>
#include <QPushButton>

#include <cmath>

#include "sim/terrain_file.h"
#include "ui/icons.h"

namespace sp {
namespace {

QString qs(const std::string& s) { return QString::fromStdString(s); }

// Writes `grid` to `terrainFile` and the world `base` with that terrain to
// `worldFile`; "" or why not.
QString writeTerrain(const HeightGrid& grid, const std::string& base, const QString& terrainFile, const QString& worldFile) {
  std::string error;
  if (!saveHeightGrid(terrainFile.toStdString(), grid, error) ||
      !saveWorldWithTerrain(base, worldFile.toStdString(), terrainFile.toStdString(), grid, error))
    return qs(error);
  return {};
}

// OK and Cancel under `form`; whether the dialog was accepted.
bool askOkCancel(QDialog& dialog, QFormLayout* form) {
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, &dialog);
  form->addRow(buttons);
  QObject::connect(buttons, &QDialogButtonBox::accepted, &dialog, &QDialog::accept);
  QObject::connect(buttons, &QDialogButtonBox::rejected, &dialog, &QDialog::reject);
  return dialog.exec() == QDialog::Accepted;
}

// "<folder>/<stem>.world.xml" beside a terrain file.
QString worldBeside(const QString& terrainFile) {
  const QFileInfo f(terrainFile);
  return f.absolutePath() + QStringLiteral("/") + f.completeBaseName() + QStringLiteral(".world.xml");
}

}  // namespace

TerrainPanel::TerrainPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  editButton_ = new QPushButton(tr("Edit terrain"), this);
  editButton_->setCheckable(true);
  editButton_->setToolTip(tr("The left button paints the ground in the 3D view; right drag and wheel move the camera"));
  layout->addWidget(editButton_);

  auto* form = new QFormLayout;
  kind_ = new QComboBox(this);
  for (BrushKind k : {BrushKind::Raise, BrushKind::Lower, BrushKind::Smooth, BrushKind::Flatten, BrushKind::Noise})
    kind_->addItem(actionIcon(QStringLiteral("brush-") + QLatin1String(brushName(k))), QString::fromLatin1(brushName(k)),
                   static_cast<int>(k));
  radius_ = new QDoubleSpinBox(this);
  radius_->setRange(0.1, 20);
  radius_->setSingleStep(0.1);
  radius_->setValue(1.0);
  radius_->setSuffix(QStringLiteral(" m"));
  strength_ = new QDoubleSpinBox(this);
  strength_->setDecimals(3);
  strength_->setRange(0.001, 1);
  strength_->setSingleStep(0.005);
  strength_->setValue(0.02);
  flatten_ = new QDoubleSpinBox(this);
  flatten_->setDecimals(3);
  flatten_->setRange(-1000, 1000);
  flatten_->setSuffix(QStringLiteral(" m"));
  pick_ = new QPushButton(tr("Pick"), this);
  pick_->setToolTip(tr("Click the ground in the 3D view to flatten to its height"));
  auto* flattenRow = new QHBoxLayout;
  flattenRow->addWidget(flatten_, 1);
  flattenRow->addWidget(pick_);
  form->addRow(tr("Brush"), kind_);
  form->addRow(tr("Radius"), radius_);
  form->addRow(tr("Strength"), strength_);
  form->addRow(tr("Flatten to"), flattenRow);
  layout->addLayout(form);

  auto* history = new QHBoxLayout;
  undo_ = new QPushButton(tr("Undo"), this);
  redo_ = new QPushButton(tr("Redo"), this);
  history->addWidget(undo_);
  history->addWidget(redo_);
  layout->addLayout(history);
  auto* files = new QHBoxLayout;
  auto* newButton = new QPushButton(tr("New…"), this);
  newButton->setToolTip(tr("A flat terrain of a size, resolution and height of your choice"));
  auto* importButton = new QPushButton(tr("Import…"), this);
  importButton->setToolTip(tr("A grid (.asc, .pgm, .csv) or a 1-D profile (distance,height), as the test track"));
  save_ = new QPushButton(tr("Save as…"), this);
  save_->setToolTip(tr("The edited terrain as .asc, .pgm or .csv, and the world file that uses it"));
  files->addWidget(newButton);
  files->addWidget(importButton);
  files->addWidget(save_);
  layout->addLayout(files);
  preview_ = new QLabel(tr("Point at the ground to see its height and what a dab adds."), this);
  preview_->setWordWrap(true);
  risk_ = new QLabel(this);
  risk_->setWordWrap(true);
  risk_->setStyleSheet(QStringLiteral("QLabel { background: #f0a030; color: black; padding: 3px; }"));
  risk_->hide();
  layout->addWidget(preview_);
  layout->addWidget(risk_);
  state_ = new QLabel(this);
  state_->setWordWrap(true);
  reach_ = new QLabel(this);
  reach_->setWordWrap(true);
  layout->addWidget(state_);
  layout->addWidget(reach_);
  layout->addStretch(1);

  connect(editButton_, &QPushButton::toggled, this, [this](bool on) {
    updateState();
    emit editingChanged(on);
  });
  connect(radius_, &QDoubleSpinBox::valueChanged, this, [this](double r) { emit brushRadiusChanged(r); });
  connect(kind_, &QComboBox::currentIndexChanged, this, [this] {
    const auto k = static_cast<BrushKind>(kind_->currentData().toInt());
    const bool fraction = k == BrushKind::Smooth || k == BrushKind::Flatten;
    strength_->setSuffix(fraction ? QString() : QStringLiteral(" m"));
    strength_->setToolTip(fraction ? tr("How far each dab goes towards the target (0..1)")
                                   : tr("Height added at the centre per dab [m]"));
    flatten_->setEnabled(k == BrushKind::Flatten);
    pick_->setEnabled(k == BrushKind::Flatten);
  });
  kind_->currentIndexChanged(0);
  connect(pick_, &QPushButton::clicked, this, [this] { emit pickRequested(); });
  connect(undo_, &QPushButton::clicked, this, &TerrainPanel::undo);
  connect(redo_, &QPushButton::clicked, this, &TerrainPanel::redo);
  connect(newButton, &QPushButton::clicked, this, &TerrainPanel::askNew);
  connect(importButton, &QPushButton::clicked, this, &TerrainPanel::askImport);
  connect(save_, &QPushButton::clicked, this, &TerrainPanel::askSave);
  updateState();
}

TerrainPanel::~TerrainPanel() = default;

void TerrainPanel::setTerrain(const WorldModel* world, TerrainEditor* editor) {
  world_ = world;
  editor_ = world ? editor : nullptr;
  lastDab_.reset();
  limits_ = world ? drivableLimits(*world) : std::nullopt;
  wheelRadius_ = limits_ ? world->robots[0].model.drive->wheelRadius : 0.0;
  showRisk(std::nullopt, false);
  if (!editor_) setEditing(false);
  updateState();
}

void TerrainPanel::setBrush(const Brush& brush) {
  kind_->setCurrentIndex(kind_->findData(static_cast<int>(brush.kind)));
  radius_->setValue(brush.radius);
  strength_->setValue(brush.strength);
  flatten_->setValue(brush.target);
}

Brush TerrainPanel::brush() const {
  return Brush{static_cast<BrushKind>(kind_->currentData().toInt()), radius_->value(), strength_->value(),
               flatten_->value(), seed_};
}

void TerrainPanel::setEditing(bool on) { editButton_->setChecked(on && editor_); }

bool TerrainPanel::editing() const { return editButton_->isChecked(); }

void TerrainPanel::dabAt(const Vec3& ground) {
  if (!editor_ || !world_) return;
  const Vec2 at = gridPoint(world_->terrain, {ground.x, ground.y});
  const Brush b = brush();
  if (lastDab_ && std::hypot(at.x - lastDab_->x, at.y - lastDab_->y) < b.radius / 4) return;
  lastDab_ = at;
  if (std::optional<TerrainPatchCmd> p = editor_->dab(at, b)) {
    if (limits_) showRisk(strokeRisk(editor_->grid(), *p, *limits_, wheelRadius_), true);
    emit patch(*p);
  }
}

void TerrainPanel::hoverAt(const Vec3& ground) {
  if (!editor_ || !world_) return;
  const Vec2 at = gridPoint(world_->terrain, {ground.x, ground.y});
  const HeightGrid& grid = editor_->grid();
  const std::optional<TerrainPatchCmd> next = brushDab(grid, at, brush());
  // What the dab would do at the sample nearest the cursor.
  double dab = 0;
  if (next) {
    const int i = static_cast<int>(std::lround((at.x + grid.width / 2) / grid.spacingX())) - next->column;
    const int j = static_cast<int>(std::lround((at.y + grid.depth / 2) / grid.spacingY())) - next->row;
    if (i >= 0 && i < next->columns && j >= 0 && j < next->rows)
      dab = next->heights[static_cast<size_t>(j * next->columns + i)] - grid.at(i + next->column, j + next->row);
  }
  const double here = grid.heightAt(at.x, at.y) + world_->terrain.pose.p.z;
  QString text = tr("Here: ground %1 m").arg(here, 0, 'f', 3);
  if (editor_->inStroke()) text += tr("; this stroke %1 m").arg(editor_->strokeChange(at), 0, 'f', 3, QLatin1Char(' '));
  text += next ? tr("; a dab %1%2 m").arg(dab >= 0 ? "+" : "").arg(dab, 0, 'f', 3) : tr("; off the grid");
  preview_->setText(text);
  // While a stroke is open its dabs say what they made (dabAt): checking
  // the would-be dab too would do the same work twice per mouse move.
  if (!limits_ || editor_->inStroke()) return;
  showRisk(next ? strokeRisk(grid, *next, *limits_, wheelRadius_) : std::nullopt, false);
}

void TerrainPanel::showRisk(const std::optional<TerrainRisk>& risk, bool made) {
  if (risk) {
    Vec2 w = worldPoint(world_->terrain, risk->at);
    for (double* c : {&w.x, &w.y})
      if (std::abs(*c) < 0.05) *c = 0;  // "-0.0" reads as a direction
    risk_->setText((made ? tr("This stroke made %1, at (%2, %3) m.") : tr("A dab here would make %1, at (%2, %3) m."))
                       .arg(QString::fromStdString(risk->message(*limits_)))
                       .arg(w.x, 0, 'f', 1)
                       .arg(w.y, 0, 'f', 1));
    risk_->setToolTip(QString::fromStdString("From the robot's files: " + limits_->basis));
  }
  risk_->setVisible(risk.has_value());
  if (risky_ != risk.has_value()) {
    risky_ = risk.has_value();
    emit riskChanged(risky_);
  }
}

QString TerrainPanel::riskText() const { return risk_->isVisible() ? risk_->text() : QString(); }

QString TerrainPanel::previewText() const { return preview_->text(); }

void TerrainPanel::endStroke() {
  lastDab_.reset();
  if (!editor_) return;
  const bool open = editor_->inStroke();
  editor_->endStroke();
  if (open) ++seed_;  // the next noise stroke draws other values
  updateState();
  emit strokeEnded();
}

void TerrainPanel::undo() {
  if (!editor_) return;
  if (std::optional<TerrainPatchCmd> p = editor_->undo()) {
    emit patch(*p);
    emit strokeEnded();
  }
  updateState();
}

void TerrainPanel::redo() {
  if (!editor_) return;
  if (std::optional<TerrainPatchCmd> p = editor_->redo()) {
    emit patch(*p);
    emit strokeEnded();
  }
  updateState();
}

void TerrainPanel::setFlattenHeight(double height) {
  // The brush works in the grid's own heights; the world adds the terrain's z.
  flatten_->setValue(height - (world_ ? world_->terrain.pose.p.z : 0.0));
}

void TerrainPanel::setReach(const QString& text) { reach_->setText(text); }

void TerrainPanel::updateState() {
  const bool can = editor_ != nullptr;
  editButton_->setEnabled(can);
  undo_->setEnabled(can && editor_->undoLevels() > 0);
  redo_->setEnabled(can && editor_->redoLevels() > 0);
  save_->setEnabled(can);
  if (!can) {
    state_->setText(tr("This world's ground is a plane: New… or Import… a heightfield to edit."));
    return;
  }
  const HeightGrid& g = editor_->grid();
  state_->setText(tr("%1 × %2 samples over %3 × %4 m; %5 undo, %6 redo levels")
                      .arg(g.columns)
                      .arg(g.rows)
                      .arg(g.width, 0, 'g', 4)
                      .arg(g.depth, 0, 'g', 4)
                      .arg(editor_->undoLevels())
                      .arg(editor_->redoLevels()));
}

QString TerrainPanel::save(const QString& terrainFile, const QString& worldFile) {
  if (!editor_ || !world_) return tr("no heightfield to save");
  QString error = writeTerrain(editor_->grid(), world_->file, terrainFile, worldFile);
  if (error.isEmpty()) editor_->markSaved();
  return error;
}

QString TerrainPanel::createNew(double width, double depth, double resolution, double baseHeight,
                                const QString& terrainFile, const QString& worldFile) {
  if (!world_) return tr("no world to base the new one on");
  if (!(width > 0 && depth > 0 && resolution > 0) || !std::isfinite(baseHeight))
    return tr("width, depth and resolution must be > 0, the height finite");
  const int columns = static_cast<int>(std::lround(width / resolution)) + 1;
  const int rows = static_cast<int>(std::lround(depth / resolution)) + 1;
  if (columns > 4096 || rows > 4096) return tr("at most 4096 × 4096 samples: %1 × %2 asked").arg(columns).arg(rows);
  HeightGrid grid{columns, rows, width, depth, std::vector<double>(static_cast<size_t>(columns) * rows, baseHeight)};
  return writeTerrain(grid, world_->file, terrainFile, worldFile);
}

QString TerrainPanel::import(const QString& source, bool profile, double width, double depth, double resolution,
                             const QString& terrainFile, const QString& worldFile) {
  if (!world_) return tr("no world to base the new one on");
  TerrainSource from;
  from.path = source.toStdString();
  from.format = profile ? TerrainFormat::Profile : TerrainFormat::Auto;
  from.width = width;
  from.depth = depth;
  from.resolution = resolution;
  Diagnostics diag;
  const std::optional<HeightGrid> grid = loadHeightGrid(from, diag);
  if (!grid) return qs(diag.format()).trimmed();
  return writeTerrain(*grid, world_->file, terrainFile, worldFile);
}

void TerrainPanel::askSave() {
  const QString file = QFileDialog::getSaveFileName(this, tr("Save terrain"), QString(),
                                                    tr("Terrain (*.asc *.pgm *.csv)"));
  if (file.isEmpty()) return;
  const QString world = worldBeside(file);
  if (const QString e = save(file, world); !e.isEmpty()) QMessageBox::warning(this, tr("Save terrain"), e);
  else QMessageBox::information(this, tr("Save terrain"), tr("Saved %1\nand the world that uses it, %2").arg(file, world));
}

namespace {

QDoubleSpinBox* metres(QWidget* parent, double value, double min, double max) {
  auto* box = new QDoubleSpinBox(parent);
  box->setDecimals(3);
  box->setRange(min, max);
  box->setValue(value);
  box->setSuffix(QStringLiteral(" m"));
  return box;
}

}  // namespace

void TerrainPanel::askNew() {
  QDialog dialog(this);
  dialog.setWindowTitle(tr("New terrain"));
  auto* form = new QFormLayout(&dialog);
  QDoubleSpinBox* width = metres(&dialog, 20, 0.1, 10000);
  QDoubleSpinBox* depth = metres(&dialog, 20, 0.1, 10000);
  QDoubleSpinBox* resolution = metres(&dialog, 0.1, 0.005, 100);
  QDoubleSpinBox* base = metres(&dialog, 0, -1000, 1000);
  form->addRow(tr("Width (x)"), width);
  form->addRow(tr("Depth (y)"), depth);
  form->addRow(tr("Resolution"), resolution);
  form->addRow(tr("Height"), base);
  if (!askOkCancel(dialog, form)) return;
  writeAndOpen(tr("New terrain"), [&](const QString& file, const QString& world) {
    return createNew(width->value(), depth->value(), resolution->value(), base->value(), file, world);
  });
}

void TerrainPanel::writeAndOpen(const QString& title, const std::function<QString(const QString&, const QString&)>& write) {
  const QString file =
      QFileDialog::getSaveFileName(this, tr("%1: save the terrain as").arg(title), QString(), tr("Terrain (*.asc *.pgm *.csv)"));
  if (file.isEmpty()) return;
  const QString world = worldBeside(file);
  if (const QString e = write(file, world); !e.isEmpty()) QMessageBox::warning(this, title, e);
  else emit openWorldRequested(world);
}

void TerrainPanel::askImport() {
  const QString source = QFileDialog::getOpenFileName(this, tr("Import terrain"), QString(),
                                                      tr("Grids and profiles (*.asc *.pgm *.csv);;All files (*)"));
  if (source.isEmpty()) return;
  QDialog dialog(this);
  dialog.setWindowTitle(tr("Import %1").arg(QFileInfo(source).fileName()));
  auto* form = new QFormLayout(&dialog);
  auto* kind = new QComboBox(&dialog);
  kind->addItem(tr("a grid of heights"));
  kind->addItem(tr("a 1-D profile (distance,height), extruded sideways"));
  QDoubleSpinBox* width = metres(&dialog, 0, 0, 10000);
  width->setSpecialValueText(tr("from the file"));
  QDoubleSpinBox* depth = metres(&dialog, 4, 0, 10000);
  QDoubleSpinBox* resolution = metres(&dialog, 0.05, 0.005, 100);
  form->addRow(tr("The file is"), kind);
  form->addRow(tr("Width (x)"), width);
  form->addRow(tr("Depth (y)"), depth);
  form->addRow(tr("Resolution (profile)"), resolution);
  if (!askOkCancel(dialog, form)) return;
  writeAndOpen(tr("Import terrain"), [&](const QString& file, const QString& world) {
    return import(source, kind->currentIndex() == 1, width->value(), depth->value(), resolution->value(), file, world);
  });
}

}  // namespace sp
