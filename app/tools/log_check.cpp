// simpartner-logcheck: checks a session log left by a killed writer
// (scripts/crash_test.sh, docs/session-format.md "Crash safety").
//
//   simpartner-logcheck LOG [--killed-at EPOCH_S] [--rtf F] [--max-loss-ms MS]
//
// Checks that LOG opens as a session log of this format version
// (SessionLogReader), that `PRAGMA integrity_check` answers "ok" and, with
// --killed-at, that the last committed sample is at most MS (default 100)
// behind the sim time the run can have reached when it was killed.
//
// That bound: the writer creates LOG before the run's pacer starts, so the
// run started no earlier than LOG's birth time (statx btime). At real-time
// factor F the pacer never runs sim time ahead of wall time x F, so at the
// kill the sim time was at most (killed_at - birth) x F. The loss printed,
// (killed_at - birth) x F - last sample time, is therefore an upper bound
// on what was lost. Both times are CLOCK_REALTIME (the kernel stamps btime
// with it; the script reads $EPOCHREALTIME), so they compare directly.
//
// Prints what is wrong (a log without samples is not ok), then one line
// "ok|FAIL loss_ms=... last_time=... samples=..." and exits
// 0 when all checks pass, 1 otherwise, 2 on bad usage, 3 when LOG is an
// empty database (the writer was killed before its first commit).

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "app/log/session_log.h"

namespace {

// LOG's birth time [s since the epoch], or a negative value if unknown.
double birthTime(const std::string& path) {
  struct statx sx {};
  if (statx(AT_FDCWD, path.c_str(), 0, STATX_BTIME, &sx) != 0 || !(sx.stx_mask & STATX_BTIME)) return -1;
  return static_cast<double>(sx.stx_btime.tv_sec) + 1e-9 * static_cast<double>(sx.stx_btime.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: simpartner-logcheck LOG [--killed-at EPOCH_S] [--rtf F] [--max-loss-ms MS]\n");
    return 2;
  }
  const std::string path = argv[1];
  double killedAt = -1, rtf = 1, maxLossMs = 100;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const double v = std::atof(argv[i + 1]);
    if (a == "--killed-at") killedAt = v;
    else if (a == "--rtf") rtf = v;
    else if (a == "--max-loss-ms") maxLossMs = v;
    else {
      std::fprintf(stderr, "simpartner-logcheck: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  // The birth time first: opening the log may recover the WAL, but that
  // does not change the main file's btime anyway.
  const double birth = birthTime(path);

  sqlite3* db = nullptr;
  if (sp::openSessionLogReadOnly(path, &db) != SQLITE_OK) {
    std::printf("FAIL open: %s\n", db ? sqlite3_errmsg(db) : "out of memory");
    sqlite3_close(db);
    return 1;
  }
  std::string error;
  if (!sp::SessionLogReader::open(path, error)) {
    // Killed between creating the file and committing the schema: SQLite
    // rolls that first transaction back, leaving a database with no tables.
    // Nothing was logged yet, so nothing was lost.
    sqlite3_stmt* st = nullptr;
    long long tables = -1;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM sqlite_master", -1, &st, nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW)
      tables = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    if (tables == 0) {
      std::printf("empty: killed before the schema was committed\n");
      return 3;
    }
    std::printf("FAIL open: %s\n", error.c_str());
    return 1;
  }
  std::string integrity;
  double lastTime = -1;
  long long samples = 0;
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &st, nullptr) == SQLITE_OK) {
    while (sqlite3_step(st) == SQLITE_ROW) {
      const unsigned char* t = sqlite3_column_text(st, 0);
      if (!integrity.empty()) integrity += "; ";
      integrity += t ? reinterpret_cast<const char*>(t) : "";
    }
  }
  sqlite3_finalize(st);
  // A log that cannot be asked for its samples (the table dropped) or has
  // none holds nothing to replay: not ok, whatever its integrity.
  std::string samplesProblem;
  if (sqlite3_prepare_v2(db, "SELECT max(time), count(*) FROM samples", -1, &st, nullptr) == SQLITE_OK &&
      sqlite3_step(st) == SQLITE_ROW) {
    if (sqlite3_column_type(st, 0) != SQLITE_NULL) lastTime = sqlite3_column_double(st, 0);
    samples = sqlite3_column_int64(st, 1);
    // Killed before the first samples' commit (--killed-at), the loss bound
    // below judges it; otherwise a log without samples is broken.
    if (samples == 0 && killedAt < 0) samplesProblem = "no samples";
  } else {
    samplesProblem = std::string("samples unreadable: ") + sqlite3_errmsg(db);
  }
  sqlite3_finalize(st);
  sqlite3_close(db);

  bool ok = integrity == "ok" && samplesProblem.empty();
  if (!samplesProblem.empty()) std::printf("FAIL %s: %s\n", path.c_str(), samplesProblem.c_str());
  double lossMs = 0;
  if (killedAt >= 0) {
    if (birth < 0) {
      std::printf("FAIL %s: no birth time on this file system, cannot bound the loss\n", path.c_str());
      return 1;
    }
    const double simAtKill = (killedAt - birth) * rtf;
    lossMs = 1000.0 * (simAtKill - (lastTime < 0 ? 0 : lastTime));
    if (lossMs > maxLossMs) ok = false;
  }
  std::printf("%s loss_ms=%.1f last_time=%.3f samples=%lld integrity=%s\n", ok ? "ok" : "FAIL", lossMs, lastTime,
              samples, integrity.c_str());
  return ok ? 0 : 1;
}
