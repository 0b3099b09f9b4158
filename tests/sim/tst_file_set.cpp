// Tests of sp::FileSet and the loaders reading through it (sim/file_set.h):
// a world and its robot held in memory load without the disk, the set takes
// precedence over the disk, and only regular files are read from the disk.

#include <QTest>

#include <QDir>
#include <QTemporaryDir>

#include <fstream>

#include "sim/file_set.h"
#include "sim/model_loader.h"

using namespace sp;

namespace {

const char* kWorld = R"(<world name="held">
  <terrain type="plane"/>
  <robot name="r" file="../robots/mini.xml" xyz="0 0 0.5"/>
</world>
)";

const char* kRobot = R"(<robot name="%1">
  <link name="base" mass="2"><geom type="box" size="0.4 0.3 0.2"/></link>
</robot>
)";

std::string robotXml(const char* name) { return QString(kRobot).arg(name).toStdString(); }

}  // namespace

class TestFileSet : public QObject {
  Q_OBJECT

 private slots:
  // Paths compare as absolute, normal paths.
  void pathsNormalised() {
    FileSet files;
    files.add("a/b/../c.txt", "x");
    QVERIFY(files.find("a/c.txt"));
    QVERIFY(files.find(QDir::current().absoluteFilePath("a/c.txt").toStdString()));
    QCOMPARE(QString::fromStdString(*files.find("./a/c.txt")), QString("x"));
    QVERIFY(!files.find("a/b.txt"));
    files.add("a/c.txt", "y");
    QCOMPARE(files.size(), size_t{1});
    QCOMPARE(QString::fromStdString(*files.find("a/c.txt")), QString("y"));
  }

  // A world and the robot it names, held in memory under paths that do not
  // exist on the disk, load as from files (relative references resolved).
  void worldFromMemory() {
    FileSet files;
    files.add("/nonexistent/sp/worlds/held.world.xml", kWorld);
    files.add("/nonexistent/sp/robots/mini.xml", robotXml("mini"));
    Diagnostics diag;
    const std::optional<WorldModel> world = loadWorld("/nonexistent/sp/worlds/held.world.xml", diag, &files);
    QVERIFY2(world, diag.format().c_str());
    QCOMPARE(QString::fromStdString(world->robots[0].model.name), QString("mini"));
    // Without the set nothing is found.
    Diagnostics none;
    QVERIFY(!loadWorld("/nonexistent/sp/worlds/held.world.xml", none));
    QCOMPARE(QString::fromStdString(none.format()),
             QString("/nonexistent/sp/worlds/held.world.xml: error: cannot open world file: not found\n"));
  }

  // The set wins over the disk; what the set lacks comes from the disk.
  void setBeforeDisk() {
    QTemporaryDir dir;
    QVERIFY(QDir(dir.path()).mkpath("worlds") && QDir(dir.path()).mkpath("robots"));
    const std::string world = dir.filePath("worlds/held.world.xml").toStdString();
    const std::string robot = dir.filePath("robots/mini.xml").toStdString();
    std::ofstream(world) << kWorld;
    std::ofstream(robot) << robotXml("on_disk");
    FileSet files;
    files.add(robot, robotXml("in_memory"));
    Diagnostics diag;
    std::optional<WorldModel> w = loadWorld(world, diag, &files);  // the world from the disk
    QVERIFY2(w, diag.format().c_str());
    QCOMPARE(QString::fromStdString(w->robots[0].model.name), QString("in_memory"));
    w = loadWorld(world, diag);
    QVERIFY2(w, diag.format().c_str());
    QCOMPARE(QString::fromStdString(w->robots[0].model.name), QString("on_disk"));
  }

  // From the disk only regular files are read: a folder or a device that
  // never ends is refused at once, not read.
  void onlyRegularFiles() {
    QTemporaryDir dir;
    QVERIFY(!readSourceFile(dir.path().toStdString(), nullptr));
    QVERIFY(!readSourceFile("/dev/zero", nullptr));
    Diagnostics diag;
    QVERIFY(!loadRobot("/dev/zero", diag));
    QCOMPARE(QString::fromStdString(diag.format()), QString("/dev/zero: error: cannot open robot file: it is not a regular file (a folder, device or pipe)\n"));
  }
};

QTEST_GUILESS_MAIN(TestFileSet)
#include "tst_file_set.moc"
