// Minimal data parallelism over index ranges, on a few helper threads kept
// between jobs.
//
// Starting a thread costs tens of microseconds, as much as a small mesh's
// whole stage: a split of two small meshes has four parallel stages. So the
// helpers (one fewer than the cores) are started on first use and wait for
// the next job (spinning a moment before they sleep, as the stages of one
// operation follow each other closely); each leaves after a moment without
// work, so an idle process keeps no threads. The thread that posts a job takes its chunks
// too, and runs every chunk no helper has taken by the time it has
// finished its own: every chunk runs exactly once, also when no thread can
// be started. While it waits for the helpers' chunks it takes chunks of
// the jobs those post (nested parallelism: a stage of one mesh inside a job
// over meshes), so a nested job has every idle thread, and no thread waits
// for a chunk that nobody runs.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <functional>
#include <vector>

namespace meshmend {

// Number of threads MeshMend's work runs on (at least 1): the count set
// by setThreadCount, else the environment variable MESHMEND_THREADS (a
// whole number from 1; read once, at the first use), else the CPUs the
// process may run on (taskset, cgroup cpusets), asked once, where
// hardware_concurrency counts every CPU of the machine (and reads /sys on
// every call, which costs more than a small job's work). Every operation
// of the core, the filters and the Python module follow it.
unsigned workerCount();

// Sets the number of threads from now on (0: back to MESHMEND_THREADS or
// the CPUs); helper threads beyond it leave. Call it between operations,
// not while one runs (they size per-thread results by workerCount()).
void setThreadCount(unsigned count);

// What workerCount() is when nothing is set: MESHMEND_THREADS, else the CPUs.
unsigned defaultThreadCount();

namespace detail {

// A job of `count` chunks: run(context, i) runs chunk i. Owned by the
// thread that posts it, which waits in finishJob() until every chunk is done.
struct Job {
  void (*run)(void* context, std::size_t chunk);
  void* context;
  std::size_t count;
  std::size_t claimed = 0;   // chunks taken (by any thread), under the pool's lock
  std::size_t finished = 0;  // chunks done, under the pool's lock
  int poster_cpu = -1;       // the CPU the posting thread was on (-1: unknown)
};

// Posts the job to the helpers, runs the chunks they have not taken on the
// calling thread, and returns once every chunk has finished. run() must
// not throw.
void runJob(Job& job);

// Posts a job and returns at once; finishJob() then runs the chunks still
// untaken on the calling thread (or, unless `runUntaken`, drops them) and
// waits for those a helper has taken.
void postJob(Job& job);
void finishJob(Job& job, bool runUntaken);

// Moves the calling thread off `cpu` (where it runs) onto another CPU it
// may run on, keeping the CPUs it may run on as they were. False when it
// has no other CPU (or may not run on `cpu`). The pool uses it to keep a
// helper off the CPU of the thread whose chunk it runs (parallel.cpp).
bool moveOffCpu(int cpu);

}  // namespace detail

// Asks the helper threads to leave and waits until they have (the next job
// starts them again). For a process about to give up its threads, and for
// tests that must see threads started afresh.
void releaseHelperThreads();

// Splits [0, n) into one contiguous chunk per worker and calls
// body(begin, end, worker) on each, in parallel; small ranges run inline.
// `worker` is the chunk's number (0..workerCount()-1): no two chunks of one
// call share it, so it can index per-chunk results. The first exception
// thrown by a chunk is rethrown after all chunks have finished.
template <class Body>
void parallelChunks(std::size_t n, Body&& body, std::size_t minimumPerWorker = 4096) {
  const std::size_t workers = std::max<std::size_t>(
      1, std::min<std::size_t>(workerCount(), n / std::max<std::size_t>(1, minimumPerWorker)));
  if (workers == 1) {
    body(std::size_t(0), n, 0u);
    return;
  }
  struct Context {
    Body& body;
    std::size_t n, workers;
    std::vector<std::exception_ptr> errors;
  } context{body, n, workers, std::vector<std::exception_ptr>(workers)};
  detail::Job job{[](void* c, std::size_t w) {
                    Context& x = *static_cast<Context*>(c);
                    try {
                      x.body(x.n * w / x.workers, x.n * (w + 1) / x.workers, unsigned(w));
                    } catch (...) {
                      x.errors[w] = std::current_exception();
                    }
                  },
                  &context, workers};
  detail::runJob(job);
  for (const std::exception_ptr& e : context.errors)
    if (e) std::rethrow_exception(e);
}

// Per-chunk results of parallelChunks (indexed by `worker`) as one list,
// in chunk order: a chunk's items in [0, n) order stay in that order.
template <class T>
std::vector<T> joined(const std::vector<std::vector<T>>& parts) {
  std::size_t n = 0;
  for (const auto& part : parts) n += part.size();
  std::vector<T> all;
  all.reserve(n);
  for (const auto& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

// Runs a task on a helper thread while the caller works on, or, when no
// helper takes it first, on the calling thread once it is waited for: the
// task runs exactly once either way (if waited for), and wait() rethrows
// what it threw. The destructor waits for a task a helper has taken and
// drops one none has (an error on the caller's side leaves nothing running).
class TaskAlongside {
 public:
  explicit TaskAlongside(std::function<void()> task)
      : task_(std::move(task)),
        job_{[](void* self, std::size_t) {
               TaskAlongside& t = *static_cast<TaskAlongside*>(self);
               try {
                 t.task_();
               } catch (...) {
                 t.error_ = std::current_exception();
               }
             },
             this, 1} {
    detail::postJob(job_);
  }
  TaskAlongside(const TaskAlongside&) = delete;
  TaskAlongside& operator=(const TaskAlongside&) = delete;
  ~TaskAlongside() {
    if (!waited_) detail::finishJob(job_, false);
  }
  void wait() {
    if (waited_) return;
    waited_ = true;
    detail::finishJob(job_, true);
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::function<void()> task_;
  std::exception_ptr error_;
  bool waited_ = false;
  detail::Job job_;  // last: made once the members its task uses are
};

}  // namespace meshmend
