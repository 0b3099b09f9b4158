#pragma once
// Builds worlds from small inline XML for the sim tests.

#include <QTemporaryDir>
#include <QTest>

#include <fstream>
#include <memory>
#include <string>

#include "sim/model_loader.h"
#include "sim/world.h"

namespace sp::test {

/// Writes `robotXml` (if any) as robot.xml and `worldXml` as test.world.xml
/// into a temporary folder and builds the world. Fails the test on any
/// diagnostic, warnings included, so tests notice unexpected messages.
class WorldFixture {
 public:
  std::unique_ptr<World> build(const std::string& worldXml, const std::string& robotXml = {},
                               SimParams params = {}) {
    if (!robotXml.empty()) write("robot.xml", robotXml);
    const std::string path = write("test.world.xml", worldXml);
    Diagnostics diag;
    std::optional<WorldModel> model = loadWorld(path, diag);
    if (!diag.empty()) qWarning("%s", diag.format().c_str());
    if (!model || !diag.empty()) return nullptr;
    return World::create(*model, params, diag);
  }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = dir_.filePath(QString::fromStdString(name)).toStdString();
    std::ofstream(path) << text;
    return path;
  }

 private:
  QTemporaryDir dir_;
};

inline void stepFor(World& world, double seconds) {
  const auto n = static_cast<int64_t>(seconds / world.params().step + 0.5);
  for (int64_t i = 0; i < n; ++i) world.step();
}

}  // namespace sp::test
