#include "ui/jobs/jobs.h"

#include "ui/jobs/calibration/calibration_job.h"
#include "ui/jobs/drive/drive_job.h"
#include "ui/jobs/link/link_job.h"
#include "ui/jobs/replay/replay_job.h"
#include "ui/jobs/sequence/sequence_job.h"
#include "ui/jobs/terrain/terrain_job.h"
#include "ui/main_window.h"

namespace sp {

std::vector<std::unique_ptr<ConsoleJob>> builtInJobs(const ConsoleOptions& options, const QString& logDir) {
  std::vector<std::unique_ptr<ConsoleJob>> jobs;
  jobs.push_back(std::make_unique<LinkJob>(options.takeControl));
  jobs.push_back(std::make_unique<DriveJob>());
  jobs.push_back(std::make_unique<SequenceJob>(options.rules, options.sequence));
  jobs.push_back(std::make_unique<TerrainJob>());
  jobs.push_back(std::make_unique<ReplayJob>(logDir, options.replay));
  jobs.push_back(std::make_unique<CalibrationJob>());
  return jobs;
}

}  // namespace sp
