#include "ui/scene_view_impl.h"

namespace sp {

SceneView::Impl::Impl() {
  root = new osg::Group;
  worldNode = new osg::Group;
  robotNode = new osg::Group;
  root->addChild(worldNode);
  root->addChild(robotNode);
  // The ghost light blue; the rehearsal amber. The paths in the same hues,
  // saturated and opaque: a thin line in a pale tint vanishes against the
  // sky and light ground.
  buildPhantom(ghost, {kGhostTint[0], kGhostTint[1], kGhostTint[2], kGhostTint[3]}, {0.05f, 0.45f, 1.00f, 1.0f}, true);
  buildPhantom(rehearsal, {1.00f, 0.70f, 0.15f, 0.50f}, {0.95f, 0.45f, 0.00f, 1.0f}, false);
  buildLaser();
  root->addChild(laserNode);
  buildRegion();
  // The brush footprint: a yellow ring, unlit, drawn over the ground.
  footprintNode = new osg::Geode;
  footprint = newGeometry();
  footprint->setVertexArray(new osg::Vec3Array);
  auto* ringColor = new osg::Vec4Array;
  ringColor->push_back({1.0f, 0.85f, 0.1f, 1.0f});
  footprint->setColorArray(ringColor, osg::Array::BIND_OVERALL);
  footprint->addPrimitiveSet(new osg::DrawArrays(GL_LINE_LOOP, 0, 0));
  footprint->setDataVariance(osg::Object::DYNAMIC);
  footprintNode->addDrawable(footprint);
  footprintNode->getOrCreateStateSet()->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  footprintNode->getOrCreateStateSet()->setAttributeAndModes(new osg::LineWidth(2.0f));
  footprintNode->setNodeMask(0);
  root->addChild(footprintNode);

  osg::StateSet* s = root->getOrCreateStateSet();
  // Geometry colours drive ambient and diffuse; a little gloss on the shapes.
  auto* material = new osg::Material;
  material->setColorMode(osg::Material::AMBIENT_AND_DIFFUSE);
  material->setSpecular(osg::Material::FRONT_AND_BACK, {0.25f, 0.25f, 0.25f, 1.0f});
  material->setShininess(osg::Material::FRONT_AND_BACK, 32.0f);
  s->setAttributeAndModes(material);
  auto* lightModel = new osg::LightModel;
  lightModel->setAmbientIntensity({0.18f, 0.18f, 0.20f, 1.0f});
  s->setAttributeAndModes(lightModel);
  // A dim fill light from the opposite side of the sun, so faces turned away
  // from the sun still show their shape.
  auto* fill = new osg::Light(1);
  fill->setPosition({-0.5f, 0.6f, 0.4f, 0.0f});
  fill->setAmbient({0, 0, 0, 1});
  fill->setDiffuse({0.28f, 0.29f, 0.32f, 1.0f});
  fill->setSpecular({0, 0, 0, 1});
  auto* fillSource = new osg::LightSource;
  fillSource->setLight(fill);
  fillSource->setStateSetModes(*s, osg::StateAttribute::ON);
  root->addChild(fillSource);
  fog = new osg::Fog;
  fog->setMode(osg::Fog::LINEAR);
  fog->setColor(kSkyColor);
  s->setAttributeAndModes(fog);

  window = new osgViewer::GraphicsWindowEmbedded(0, 0, 1, 1);
  viewer = new osgViewer::Viewer;
  viewer->setThreadingModel(osgViewer::Viewer::SingleThreaded);
  viewer->setKeyEventSetsDone(0);  // Esc must not end the viewer
  viewer->setQuitEventSetsDone(false);
  osg::Camera* camera = viewer->getCamera();
  camera->setGraphicsContext(window);
  camera->setViewport(0, 0, 1, 1);
  camera->setClearColor(kSkyColor);
  // The sun: a directional light fixed in the world, high up towards +x, -y.
  viewer->setLightingMode(osg::View::SKY_LIGHT);
  osg::Light* sun = viewer->getLight();
  sun->setPosition({0.45f, -0.35f, 0.82f, 0.0f});
  sun->setAmbient({0.30f, 0.30f, 0.32f, 1.0f});
  sun->setDiffuse({0.80f, 0.78f, 0.72f, 1.0f});
  sun->setSpecular({0.5f, 0.5f, 0.5f, 1.0f});
  viewer->setSceneData(root);
  clock.start();
}

void SceneView::Impl::buildLaser() {
  laserNode = new osg::Geode;
  beams = newGeometry();
  beams->setVertexArray(new osg::Vec3Array);
  beams->setColorArray(new osg::Vec4Array, osg::Array::BIND_PER_VERTEX);
  beams->addPrimitiveSet(new osg::DrawArrays(GL_LINES, 0, 0));
  beams->setDataVariance(osg::Object::DYNAMIC);
  hits = newGeometry();
  hits->setVertexArray(new osg::Vec3Array);
  auto* hitColor = new osg::Vec4Array;
  hitColor->push_back(kHitPointColor);
  hits->setColorArray(hitColor, osg::Array::BIND_OVERALL);
  hits->addPrimitiveSet(new osg::DrawArrays(GL_POINTS, 0, 0));
  hits->setDataVariance(osg::Object::DYNAMIC);
  laserNode->addDrawable(beams);
  laserNode->addDrawable(hits);
  osg::StateSet* s = laserNode->getOrCreateStateSet();
  s->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  s->setAttributeAndModes(new osg::LineWidth(1.0f));
  s->setAttributeAndModes(new osg::Point(5.0f));
  makeTransparent(s);
}

// Rebuilds the beams from the stored scan and the laser's current pose.
void SceneView::Impl::updateLaser() {
  auto* bv = static_cast<osg::Vec3Array*>(beams->getVertexArray());
  auto* bc = static_cast<osg::Vec4Array*>(beams->getColorArray());
  auto* hv = static_cast<osg::Vec3Array*>(hits->getVertexArray());
  bv->clear();
  bc->clear();
  hv->clear();
  if (laser >= 0 && static_cast<size_t>(robot.sensors[laser].link) < linkWorld.size()) {
    const SensorSpec& sensor = robot.sensors[laser];
    const Pose pose = linkWorld[sensor.link] * sensor.pose;
    const osg::Vec3 origin = toOsg(pose.p);
    for (size_t k = 0; k < laserRanges.size(); ++k) {
      const double r = laserRanges[k];
      if (std::isnan(r) || r < 0) continue;  // invalid reading: nothing to show
      const bool hit = r <= sensor.maxRange;
      const double a = laserAngleMin + static_cast<double>(k) * laserAngleStep;
      const osg::Vec3 end = toOsg(transformPoint(pose, {std::cos(a) * (hit ? r : sensor.maxRange),
                                                        std::sin(a) * (hit ? r : sensor.maxRange), 0}));
      bv->push_back(origin);
      bv->push_back(end);
      bc->push_back(hit ? kBeamHitColor : kBeamMissColor);
      bc->push_back(hit ? kBeamHitColor : kBeamMissColor);
      if (hit) hv->push_back(end);
    }
  }
  static_cast<osg::DrawArrays*>(beams->getPrimitiveSet(0))->setCount(static_cast<int>(bv->size()));
  static_cast<osg::DrawArrays*>(hits->getPrimitiveSet(0))->setCount(static_cast<int>(hv->size()));
  for (osg::Array* array : {static_cast<osg::Array*>(bv), static_cast<osg::Array*>(bc),
                            static_cast<osg::Array*>(hv)})
    array->dirty();
  beams->dirtyBound();
  hits->dirtyBound();
}

// Brings the scene graph and camera up to the stored state; called before
// each frame, so setters never touch the graph.
void SceneView::Impl::sync() {
  if (footprintDirty) updateFootprint();
  if (robotDirty) {
    linkWorld = linkPoses(robot, base, joints);
    for (size_t i = 0; i < links.size() && i < linkWorld.size(); ++i) links[i]->setMatrix(toMatrix(linkWorld[i]));
    robotDirty = false;
    laserDirty = true;  // the laser rides on the robot
  }
  syncRegion();  // before the ghost's path is marked clean
  syncPhantom(ghost);
  syncPhantom(rehearsal);
  if (stale != staleShown) {
    osg::StateSet* st = robotNode->getOrCreateStateSet();
    if (stale) {
      if (!staleTint) {
        staleTint = new osg::Material;
        staleTint->setColorMode(osg::Material::OFF);
        staleTint->setDiffuse(osg::Material::FRONT_AND_BACK, {0.55f, 0.55f, 0.55f, 1});
        staleTint->setAmbient(osg::Material::FRONT_AND_BACK, {0.25f, 0.25f, 0.25f, 1});
        staleTint->setSpecular(osg::Material::FRONT_AND_BACK, {0, 0, 0, 1});
      }
      st->setAttributeAndModes(staleTint, osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
    } else {
      st->removeAttribute(staleTint.get());
    }
    staleShown = stale;
  }
  if (objectsDirty) {
    for (auto& [name, o] : objects) o.transform->setMatrix(toMatrix(o.pose));
    objectsDirty = false;
  }
  if (laserDirty) {
    updateLaser();
    laserDirty = false;
  }
  laserNode->setNodeMask(laserVisible ? ~0u : 0u);
  if (follow && hasRobot) centre = toOsgD(base.p);
  if (planeFollow && hasRobot) {
    const double x = 5 * std::round(base.p.x / 5), y = 5 * std::round(base.p.y / 5);
    planeFollow->setMatrix(osg::Matrix::translate(x, y, 0));
  }
  // Chase and top turn with the robot: the eye behind it (azimuth is where
  // the eye is seen from the centre).
  if (hasRobot && (preset == SceneView::Camera::Chase || preset == SceneView::Camera::Top))
    azimuth = heading(base.q) + kPi;
  eye = centre + osg::Vec3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                            std::sin(elevation)) *
                     distance;
  viewer->getCamera()->setViewMatrixAsLookAt(eye, centre, osg::Vec3d(0, 0, 1));
  // Fog starts behind what the camera looks at, whatever the zoom.
  fog->setStart(f(distance + 15));
  fog->setEnd(f(distance * 2 + 80));
}

void SceneView::Impl::updateHud() {
  const char* names[] = {"follow", "chase", "top", "free camera"};
  hud->setText(QStringLiteral("%1 fps · %2").arg(fps, 0, 'f', 0).arg(QLatin1String(names[static_cast<int>(preset)])));
  hud->adjustSize();
}

SceneView::SceneView(QWidget* parent) : QOpenGLWidget(parent), m_(std::make_unique<Impl>()) {
  setMinimumSize(160, 120);
  m_->hud = new QLabel(this);
  m_->hud->setAttribute(Qt::WA_TransparentForMouseEvents);
  m_->hud->setStyleSheet(QStringLiteral(
      "QLabel { color: white; background: rgba(0, 0, 0, 110); padding: 2px 6px; border-radius: 3px; }"));
  m_->hud->move(8, 8);
  m_->updateHud();
  m_->hud->show();  // children made after the parent is shown stay hidden otherwise
  m_->timer.setInterval(16);
  connect(&m_->timer, &QTimer::timeout, this, qOverload<>(&QWidget::update));
  m_->timer.start();
}

SceneView::~SceneView() {
  m_->timer.stop();
  if (!isValid()) {
    // Never shown (a start that failed): no GL object exists, and closing
    // the never-realised window would make OSG probe GL without a context
    // ("OpenGL version test failed"): let the viewer go without it.
    m_->viewer->getCamera()->setGraphicsContext(nullptr);
    m_.reset();
    return;
  }
  // OSG deletes its GL objects as the viewer goes: in our context.
  makeCurrent();
  m_.reset();
  doneCurrent();
}

void SceneView::setWorld(const WorldModel& world) {
  Impl& m = *m_;
  m.worldNode->removeChildren(0, m.worldNode->getNumChildren());
  m.robotNode->removeChildren(0, m.robotNode->getNumChildren());
  for (Impl::Phantom* p : {&m.ghost, &m.rehearsal}) {
    p->body->removeChildren(0, p->body->getNumChildren());
    p->links.clear();
  }
  m.links.clear();
  m.objects.clear();
  m.objectsDirty = false;

  m.terrain = world.terrain;
  m.mesh = {};
  const TerrainSpec& t = m.terrain;
  osg::ref_ptr<osg::Node> terrain = t.kind == TerrainSpec::Kind::Plane ? planeNode(t.pose.p.z) : heightfieldNode(t, m.mesh);
  // Matte ground, pushed back in depth so the grid lines on it always win.
  auto* matte = new osg::Material;
  matte->setColorMode(osg::Material::AMBIENT_AND_DIFFUSE);
  matte->setSpecular(osg::Material::FRONT_AND_BACK, {0, 0, 0, 1});
  terrain->getOrCreateStateSet()->setAttributeAndModes(matte);
  terrain->getOrCreateStateSet()->setAttributeAndModes(new osg::PolygonOffset(1.0f, 1.0f));
  m.gridLines = gridNode(t);
  if (t.kind == TerrainSpec::Kind::Plane) {
    // An endless plane is drawn (ground and grid) around the robot, moved
    // with it in whole 5 m steps so the lines stay on the world's metres:
    // 200 m around the origin ended where a long drive went (issue 59).
    m.planeFollow = new osg::MatrixTransform;
    m.planeFollow->setDataVariance(osg::Object::DYNAMIC);
    m.planeFollow->addChild(terrain);
    m.planeFollow->addChild(m.gridLines);
    m.worldNode->addChild(m.planeFollow);
  } else {
    m.planeFollow = nullptr;
    m.worldNode->addChild(terrain);
    m.worldNode->addChild(m.gridLines);
  }
  m.footprintDirty = true;
  m.worldNode->addChild(axesNode(groundHeight(t, 0, 0)));
  // Objects start where the file puts them; dynamic ones move with setObjectPoses.
  for (const ObjectSpec& o : world.objects) {
    osg::ref_ptr<osg::MatrixTransform> xf = new osg::MatrixTransform(toMatrix(o.pose));
    xf->addChild(geomsNode(o.geoms));
    m.worldNode->addChild(xf);
    if (!o.isStatic) {
      xf->setDataVariance(osg::Object::DYNAMIC);
      m.objects[o.name] = {xf, o.pose};
    }
  }

  m.hasRobot = !world.robots.empty() && !world.robots[0].model.links.empty();
  m.robot = m.hasRobot ? world.robots[0].model : RobotModel{};
  m.laser = -1;
  for (size_t i = 0; i < m.robot.sensors.size(); ++i) {
    const SensorSpec& s = m.robot.sensors[i];
    if (s.type == SensorType::Laser && s.link >= 0 && static_cast<size_t>(s.link) < m.robot.links.size()) {
      m.laser = static_cast<int>(i);
      break;
    }
  }
  for (const LinkSpec& link : m.robot.links) {
    osg::ref_ptr<osg::MatrixTransform> xf = new osg::MatrixTransform;
    xf->setDataVariance(osg::Object::DYNAMIC);
    osg::ref_ptr<osg::Geode> shape = geomsNode(link.geoms);
    xf->addChild(shape);
    m.robotNode->addChild(xf);
    m.links.push_back(xf);
    for (Impl::Phantom* p : {&m.ghost, &m.rehearsal}) {
      osg::ref_ptr<osg::MatrixTransform> phantom = new osg::MatrixTransform;
      phantom->setDataVariance(osg::Object::DYNAMIC);
      phantom->addChild(shape);
      p->body->addChild(phantom);
      p->links.push_back(phantom);
    }
  }
  m.base = m.hasRobot ? world.robots[0].pose * m.robot.links[0].pose : Pose{};
  m.joints.assign(m.robot.joints.size(), 0.0);
  m.linkWorld.clear();
  m.robotDirty = true;
  for (Impl::Phantom* p : {&m.ghost, &m.rehearsal}) {
    p->base = m.base;
    p->joints = m.joints;
    p->dirty = true;
    p->pathPoints.clear();
    p->envelopePoints.clear();
    p->pathDirty = true;
  }
  m.region.rehearsalBand.clear();
  m.region.rehearsalDirty = true;
  m.laserRanges.clear();
  m.laserDirty = true;
  if (!m.hasRobot) m.centre = {};
}

void SceneView::setRobotState(const Pose& base, const std::vector<double>& jointPositions) {
  m_->base = base;
  m_->joints = jointPositions;
  m_->robotDirty = true;
}

void SceneView::setObjectPoses(const std::vector<NamedPose>& objects) {
  for (const NamedPose& o : objects) {
    const auto it = m_->objects.find(o.name);
    if (it == m_->objects.end()) continue;  // not a dynamic object of this world
    it->second.pose = o.pose;
    m_->objectsDirty = true;
  }
}

void SceneView::setLaser(double angleMin, double angleStep, const std::vector<double>& ranges) {
  m_->laserAngleMin = angleMin;
  m_->laserAngleStep = angleStep;
  m_->laserRanges = ranges;
  m_->laserDirty = true;
}

Pose SceneView::drawnBasePose() const {
  if (m_->links.empty()) return {};
  const osg::Matrixd m = m_->links[0]->getMatrix();
  const osg::Vec3d t = m.getTrans();
  const osg::Quat q = m.getRotate();
  return Pose{{t.x(), t.y(), t.z()}, Quat{q.w(), q.x(), q.y(), q.z()}};
}

void SceneView::setLaserVisible(bool visible) { m_->laserVisible = visible; }
void SceneView::setStale(bool stale) { m_->stale = stale; }
bool SceneView::stale() const { return m_->stale; }
bool SceneView::laserVisible() const { return m_->laserVisible; }

void SceneView::setFollow(bool on) {
  if (on == m_->follow && (on || m_->preset == Camera::Free)) return;
  setCamera(on ? Camera::Follow : Camera::Free);
}

bool SceneView::follow() const { return m_->follow; }

void SceneView::setCamera(Camera camera) {
  Impl& m = *m_;
  const Camera was = m.preset;
  m.preset = camera;
  m.follow = camera != Camera::Free;
  if (camera == Camera::Chase) {
    m.elevation = degToRad(15);
    m.distance = 6;
  } else if (camera == Camera::Top) {
    m.elevation = kMaxElevation;
    m.distance = 18;
  }
  m.updateHud();
  update();
  if (was != camera) emit cameraChanged(camera);
}

SceneView::Camera SceneView::camera() const { return m_->preset; }

Vec3 SceneView::cameraEye() const { return {m_->eye.x(), m_->eye.y(), m_->eye.z()}; }

void SceneView::resetView() {
  m_->azimuth = kDefaultAzimuth;
  m_->elevation = kDefaultElevation;
  m_->distance = kDefaultDistance;
  m_->centre = m_->hasRobot ? toOsgD(m_->base.p) : osg::Vec3d();
}

int64_t SceneView::framesDrawn() const { return m_->frames; }
double SceneView::framesPerSecond() const { return m_->fps; }

void SceneView::initializeGL() {
  if (!isValid()) return;
  // OSG needs the context current while it realizes; Qt has made it so.
  if (!m_->viewer->isRealized()) m_->viewer->realize();
}

void SceneView::resizeGL(int w, int h) {
  // Qt passes logical pixels; OSG draws in device pixels.
  m_->dpr = devicePixelRatioF();
  m_->pixelWidth = std::max(1, static_cast<int>(std::lround(w * m_->dpr)));
  m_->pixelHeight = std::max(1, static_cast<int>(std::lround(h * m_->dpr)));
  m_->window->resized(0, 0, m_->pixelWidth, m_->pixelHeight);
  m_->window->getEventQueue()->windowResize(0, 0, m_->pixelWidth, m_->pixelHeight);
  osg::Camera* camera = m_->viewer->getCamera();
  camera->setViewport(0, 0, m_->pixelWidth, m_->pixelHeight);
  camera->setProjectionMatrixAsPerspective(kFovY, static_cast<double>(m_->pixelWidth) / m_->pixelHeight, 0.1,
                                           1000.0);
}

void SceneView::paintGL() {
  Impl& m = *m_;
  if (!isValid() || !m.viewer->isRealized()) return;
  emit frameStarting();  // sources that change every frame (the ghost) set their state now
  // QOpenGLWidget draws into its own FBO, not 0 (shared/STACK.md).
  m.window->setDefaultFboId(defaultFramebufferObject());
  m.sync();
  m.viewer->frame();
  // OSG leaves byte-aligned unpacking after texture uploads; Qt expects 4.
  QOpenGLFunctions* gl = context()->functions();
  gl->glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl->glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);

  ++m.frames;
  ++m.windowFrames;
  const qint64 now = m.clock.elapsed();
  if (now - m.windowStart >= 1000) {
    m.fps = 1000.0 * static_cast<double>(m.windowFrames) / static_cast<double>(now - m.windowStart);
    m.windowFrames = 0;
    m.windowStart = now;
    m.updateHud();
  }
}

void SceneView::mousePressEvent(QMouseEvent* event) {
  Impl& m = *m_;
  if (event->button() == Qt::LeftButton && (m.editing || m.picking)) {
    if (const std::optional<Vec3> g = groundAt(event->position())) {
      if (m.picking) {
        m.picking = false;
        unsetCursor();
        emit groundPicked(*g);
      } else {
        m.painting = true;
        emit terrainDab(*g);
      }
    }
    event->accept();
    return;
  }
  if (m_->dragButton == Qt::NoButton) {
    m_->dragButton = event->button();
    m_->lastMouse = event->position() * m_->dpr;
  }
  event->accept();
}

void SceneView::mouseMoveEvent(QMouseEvent* event) {
  Impl& m = *m_;
  if (m.editing) {
    m.hover = groundAt(event->position());
    m.footprintDirty = true;
    if (m.hover) emit terrainHover(*m.hover);
    if (m.painting && m.hover) emit terrainDab(*m.hover);
  }
  if (m.dragButton == Qt::NoButton) return;
  const QPointF p = event->position() * m.dpr;
  const QPointF d = p - m.lastMouse;
  m.lastMouse = p;
  if (m.dragButton == Qt::LeftButton) {
    if (m.preset == Camera::Chase || m.preset == Camera::Top) setCamera(Camera::Follow);
    m.azimuth -= d.x() * kOrbitRadPerPixel;
    m.elevation = std::clamp(m.elevation + d.y() * kOrbitRadPerPixel, kMinElevation, kMaxElevation);
  } else if (m.dragButton == Qt::RightButton || m.dragButton == Qt::MiddleButton) {
    // Drag the ground under the cursor: the centre moves against the mouse,
    // in the image plane, by the metres one pixel spans at the centre.
    if (m.follow) setFollow(false);
    const double metresPerPixel = 2 * m.distance * std::tan(degToRad(kFovY) / 2) / m.pixelHeight;
    const osg::Vec3d forward(-std::cos(m.elevation) * std::cos(m.azimuth),
                             -std::cos(m.elevation) * std::sin(m.azimuth), -std::sin(m.elevation));
    const osg::Vec3d right(-std::sin(m.azimuth), std::cos(m.azimuth), 0);
    const osg::Vec3d up = right ^ forward;
    m.centre += (right * -d.x() + up * d.y()) * metresPerPixel;
  }
  event->accept();
}

void SceneView::mouseReleaseEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton && m_->painting) {
    m_->painting = false;
    emit terrainStrokeEnded();
  }
  if (event->button() == m_->dragButton) m_->dragButton = Qt::NoButton;
  event->accept();
}

void SceneView::wheelEvent(QWheelEvent* event) {
  // One notch (120) zooms by 12 %.
  const double notches = event->angleDelta().y() / 120.0;
  m_->distance = std::clamp(m_->distance * std::pow(0.88, notches), kMinDistance, kMaxDistance);
  event->accept();
}

void setSceneSurfaceFormat() {
  QSurfaceFormat format;
  format.setVersion(2, 1);
  format.setProfile(QSurfaceFormat::CompatibilityProfile);
  format.setDepthBufferSize(24);
  format.setSamples(0);
  format.setSwapInterval(0);  // the view paces itself with a timer
  QSurfaceFormat::setDefaultFormat(format);
}

}  // namespace sp
