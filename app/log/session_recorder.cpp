#include "app/log/session_recorder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/log/resimulation.h"  // hashHex
#include "sim/hash.h"

namespace sp {
std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string fileHash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  return hashHex(fnv1a64(readWholeFile(path)));
}

std::unique_ptr<SessionLogWriter> openSessionLog(const std::string& path, const SessionSources& sources,
                                                 std::string& error, const SessionLogOptions& options) {
  SessionInfo info;
#ifdef SP_VERSION
  info.programVersion = SP_VERSION;
#endif
  info.files.push_back({"world", sources.worldFile, readWholeFile(sources.worldFile)});
  info.files.push_back({"robot", sources.robotFile, readWholeFile(sources.robotFile)});
  if (!sources.paramsFile.empty())
    info.files.push_back({"params", sources.paramsFile, readWholeFile(sources.paramsFile)});
  if (!sources.terrainFile.empty())
    info.files.push_back({"terrain", sources.terrainFile, readWholeFile(sources.terrainFile)});
  if (!sources.commandsFile.empty())
    info.files.push_back({"commands", sources.commandsFile, readWholeFile(sources.commandsFile)});
  info.extraMeta = sources.extraMeta;
  if (!sources.replacedRobotFile.empty()) info.extraMeta["replaced_robot_file"] = sources.replacedRobotFile;
  std::unique_ptr<SessionLogWriter> writer = SessionLogWriter::open(path, info, error, options);
  if (writer)
    for (const std::string& o : sources.overrides) writer->logEvent(0, 0, "param_override", o);
  return writer;
}

std::string newSessionLogPath(const std::string& dir, std::string& error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    error = dir + ": cannot create the session log folder: " + ec.message();
    return {};
  }
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "session-%Y%m%d-%H%M%S", &local);
  // Two starts within a second get -2, -3, ...; the writer refuses to
  // replace a file, so a race with another process fails loudly instead.
  for (int n = 1; n < 1000; ++n) {
    const fs::path candidate =
        fs::path(dir) / (std::string(stamp) + (n > 1 ? "-" + std::to_string(n) : "") + ".splog");
    if (!fs::exists(candidate, ec)) return candidate.string();
  }
  error = dir + ": no free session log name for " + stamp;
  return {};
}

std::vector<SessionLogFile> listSessionLogs(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<SessionLogFile> out;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    if (p.extension() != ".splog" || !it->is_regular_file(ec)) continue;
    SessionLogFile f;
    f.path = p.string();
    for (const char* suffix : {"", "-wal", "-shm"}) {
      const uintmax_t n = fs::file_size(f.path + suffix, ec);
      if (!ec) f.bytes += n;
    }
    ec.clear();
    const auto t = fs::last_write_time(p, ec);
    if (!ec)
      f.modified = std::chrono::duration_cast<std::chrono::seconds>(
                       std::chrono::file_clock::to_sys(t).time_since_epoch())
                       .count();
    ec.clear();
    out.push_back(std::move(f));
  }
  std::sort(out.begin(), out.end(), [](const SessionLogFile& a, const SessionLogFile& b) {
    return a.modified != b.modified ? a.modified > b.modified : a.path > b.path;
  });
  return out;
}

std::string deleteSessionLog(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::remove(path, ec) || ec) return path + ": cannot delete: " + (ec ? ec.message() : "no such file");
  for (const char* suffix : {"-wal", "-shm"}) std::filesystem::remove(path + suffix, ec);
  return {};
}

std::vector<std::string> pruneSessionLogs(const std::string& dir, int keep, const std::string& current) {
  std::vector<std::string> deleted;
  if (keep <= 0) return deleted;
  int kept = 0;
  std::error_code ec;
  for (const SessionLogFile& f : listSessionLogs(dir)) {
    const bool isCurrent = !current.empty() && std::filesystem::equivalent(f.path, current, ec);
    if (isCurrent || kept < keep) {
      ++kept;
      continue;
    }
    if (deleteSessionLog(f.path).empty()) deleted.push_back(f.path);
  }
  return deleted;
}

SessionRecorder::SessionRecorder(std::unique_ptr<SessionLogWriter> writer, const World& world)
    : writer_(std::move(writer)),
      sampleEvery_(std::max<int64_t>(1, std::llround(1.0 / (world.params().logRate * world.params().step)))),
      snapshotEvery_(std::max<int64_t>(1, std::llround(1.0 / world.params().step))) {}

void SessionRecorder::snapshot(const World& world) {
  const uint64_t hash = world.stateHash();
  writer_->logSnapshot(world.snapshot(), world.time(), hash);
  writer_->logHash(world.stepCount(), hash);
  lastSnapshot_ = world.stepCount();
}

void SessionRecorder::start(const World& world) {
  snapshot(world);
  writer_->logSample(makeLogSample(world));
}

void SessionRecorder::stepped(const World& world) {
  const int64_t step = world.stepCount();
  if (step % sampleEvery_ == 0) writer_->logSample(makeLogSample(world));
  for (auto [robot, sensor] : world.sampledLastStep())
    if (robot == 0)
      if (auto scan = makeLogLaser(world.sensorSample(robot, sensor))) writer_->logLaser(std::move(*scan));
  if (step % snapshotEvery_ == 0) snapshot(world);
}

void SessionRecorder::finish(const World& world) {
  // A diverged world's state is not one to restore or compare against.
  if (world.stepCount() != lastSnapshot_ && world.health().healthy()) snapshot(world);
}

bool SessionRecorder::newlyFailed() {
  if (toldFailure_ || !writer_->failed()) return false;
  toldFailure_ = true;
  return true;
}

}  // namespace sp
