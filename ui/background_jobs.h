#pragma once
// Long work off the GUI thread, with progress and Cancel: opening or
// verifying a log, re-simulating to a branch point, rehearsing, a robustness
// check, submitting a sweep. Each job runs on a thread of its own; what it
// returns runs back on the GUI thread, unless the job was cancelled or its
// owner is gone (then it is dropped: hotspot's stale results by job id).
//
//   jobs.run(this, tr("Opening %1").arg(name), [path](const BackgroundJobs::Progress& progress) {
//     auto player = open(path, progress);                // on the worker
//     return [player] { show(player); };                 // back on the GUI thread
//   });
//
// Thread: GUI thread only (construction, every method, every signal). The
// destructor cancels every job and joins its thread.

#include <QObject>
#include <QPointer>
#include <QString>

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <thread>

namespace sp {

class BackgroundJobs : public QObject {
  Q_OBJECT

 public:
  /// Called by the work with its progress (0..1); false = cancelled, stop.
  /// May be called from the worker only.
  using Progress = std::function<bool(double)>;
  /// The work, on the worker: returns what to do on the GUI thread (may be empty).
  using Work = std::function<std::function<void()>(const Progress&)>;

  using QObject::QObject;
  ~BackgroundJobs() override;

  /// Starts `work` as job `what` for `owner` (its results are dropped if
  /// `owner` is destroyed first). Returns the job's id (> 0).
  int run(QObject* owner, const QString& what, Work work);
  /// Asks job `id` to stop (its work sees progress() return false).
  void cancel(int id);
  /// Whether job `id` is still running.
  bool running(int id) const { return jobs_.count(id) > 0; }
  /// How many jobs run now.
  int count() const { return static_cast<int>(jobs_.size()); }

 signals:
  /// Job `id` reports `fraction` (0..1) done.
  void progressed(int id, double fraction);
  /// Job `id` ended; `cancelled` when it was asked to stop (its result is
  /// dropped). Emitted just before its result runs.
  void finished(int id, bool cancelled);

 private:
  struct Job {
    QString what;
    std::shared_ptr<std::atomic<bool>> cancel;
    std::thread thread;
  };
  void reap(int id);

  std::map<int, Job> jobs_;
  int next_ = 1;
};

}  // namespace sp
