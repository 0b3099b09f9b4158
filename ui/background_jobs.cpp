#include "ui/background_jobs.h"

#include <QMetaObject>

namespace sp {

BackgroundJobs::~BackgroundJobs() {
  for (auto& [id, job] : jobs_) *job.cancel = true;
  for (auto& [id, job] : jobs_)
    if (job.thread.joinable()) job.thread.join();
}

int BackgroundJobs::run(QObject* owner, const QString& what, Work work) {
  const int id = next_++;
  Job& job = jobs_[id];
  job.what = what;
  job.cancel = std::make_shared<std::atomic<bool>>(false);
  QPointer<QObject> guard(owner);
  job.thread = std::thread([this, id, cancel = job.cancel, guard, work = std::move(work)] {
    std::function<void()> done = work([this, id, cancel](double f) {
      QMetaObject::invokeMethod(this, [this, id, f] { emit progressed(id, f); }, Qt::QueuedConnection);
      return !cancel->load();
    });
    // Back on the GUI thread: `this` outlives the thread (the destructor joins it).
    QMetaObject::invokeMethod(
        this,
        [this, id, cancel, guard, done = std::move(done)] {
          reap(id);
          const bool cancelled = cancel->load();
          emit finished(id, cancelled);
          if (!cancelled && guard && done) done();
        },
        Qt::QueuedConnection);
  });
  return id;
}

void BackgroundJobs::cancel(int id) {
  if (auto it = jobs_.find(id); it != jobs_.end()) *it->second.cancel = true;
}

void BackgroundJobs::reap(int id) {
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return;
  if (it->second.thread.joinable()) it->second.thread.join();  // it has returned already
  jobs_.erase(it);
}

}  // namespace sp
