#include "ui/jobs/jobs.h"

#include <QCommandLineParser>

#include "ui/jobs/calibration/calibration_job.h"
#include "ui/jobs/drive/drive_job.h"
#include "ui/jobs/link/link_job.h"
#include "ui/jobs/replay/replay_job.h"
#include "ui/jobs/sequence/sequence_job.h"
#include "ui/jobs/terrain/terrain_job.h"

namespace sp {

ConsoleJobs builtInJobs() {
  ConsoleJobs jobs;
  jobs.push_back(std::make_unique<LinkJob>());
  jobs.push_back(std::make_unique<DriveJob>());
  jobs.push_back(std::make_unique<SequenceJob>());
  jobs.push_back(std::make_unique<TerrainJob>());
  jobs.push_back(std::make_unique<ReplayJob>());
  jobs.push_back(std::make_unique<CalibrationJob>());
  return jobs;
}

void addJobOptions(QCommandLineParser& parser, const ConsoleJobs& jobs) {
  for (const std::unique_ptr<ConsoleJob>& job : jobs) parser.addOptions(job->commandLineOptions());
}

QString takeJobOptions(const QCommandLineParser& parser, const ConsoleJobs& jobs) {
  for (const std::unique_ptr<ConsoleJob>& job : jobs)
    if (const QString error = job->takeCommandLine(parser); !error.isEmpty()) return error;
  return {};
}

}  // namespace sp
