#include "common/base/parallel.h"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <mutex>
#include <thread>

namespace meshmend {

namespace {

// A thread about to run a chunk of a job another thread posted leaves that
// thread's CPU (see moveOffCpu). sched_getcpu is a few nanoseconds.
void avoidPosterCpu(const detail::Job& job) {
  if (job.poster_cpu >= 0 && sched_getcpu() == job.poster_cpu) detail::moveOffCpu(job.poster_cpu);
}

// The helpers and the jobs posted to them. One per process (per copy of the
// core library: each plugin links its own), never destroyed: Release sends
// the helpers away when the library leaves the process.
class HelperPool {
 public:
  static HelperPool& instance() {
    static const bool made = [] {
      // A child of fork() has none of its parent's helpers and perhaps a
      // lock some helper held: it starts from a new pool (the old one's
      // memory is left as it is; destroying it would wait for threads
      // that are not there).
      pthread_atfork(nullptr, nullptr, [] { current() = new HelperPool; });
      current() = new HelperPool;
      static Release release;
      return true;
    }();
    (void)made;
    return *current();
  }

  void post(detail::Job& job) {
    job.poster_cpu = sched_getcpu();
    std::unique_lock<std::mutex> lock(mutex_);
    pending_.push_back(&job);
    // Enough idle helpers for this job's chunks beyond the first (which its
    // poster takes; a task alongside has one chunk, for a helper).
    const std::size_t need = job.count - (job.count > 1);
    while (idle_ < need && helpers_ < workerCount() - 1) {
      // A detached POSIX thread, not a std::thread: a std::thread's state is
      // freed by the helper after its last signal, so a process could exit
      // (release() returned) with it still allocated, which LeakSanitizer
      // reported now and then as a leak.
      pthread_t helper;
      if (pthread_create(&helper, nullptr, &HelperPool::start, this) != 0)
        break;  // no thread to spare (the process is at its limit): the chunks run here
      pthread_detach(helper);
      ++helpers_;
      ++idle_;  // counted as waiting until it takes a chunk
    }
    signal();
  }

  // While its own job has chunks left, the poster takes them; then, until
  // the helpers have finished theirs, it takes chunks of other jobs: those
  // its helpers' chunks post (a stage of one mesh inside a job over meshes)
  // would otherwise have only their own poster.
  void finish(detail::Job& job, bool runUntaken) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!runUntaken && job.claimed < job.count) {  // dropped: only the taken ones run
      job.finished += job.count - job.claimed;
      job.claimed = job.count;
      unlinkIfDone(job);
    }
    while (job.finished < job.count) {
      detail::Job* next = job.claimed < job.count ? &job
                          : pending_.empty()      ? nullptr
                                                  : pending_.front();
      if (!next) {
        const std::uint64_t seen = epoch_;
        if (!spinUntilChange(lock, seen, std::chrono::steady_clock::now() + kSpin))
          changed_.wait(lock, [&] { return epoch_ != seen; });
        continue;
      }
      const std::size_t chunk = claim(*next);
      lock.unlock();
      if (next != &job) avoidPosterCpu(*next);
      next->run(next->context, chunk);
      lock.lock();
      if (++next->finished == next->count) signal();
    }
  }

  void release() {
    std::unique_lock<std::mutex> lock(mutex_);
    stop_ = true;
    signal();
    changed_.wait(lock, [&] { return helpers_ == 0; });
    stop_ = false;
  }

 private:
  // Releases the helpers when the library leaves the process (exit, or a
  // plugin's library unloaded): no helper is left to run unmapped code.
  struct Release {
    ~Release() { current()->release(); }
  };

  static void* start(void* pool) {
    static_cast<HelperPool*>(pool)->serve();
    return nullptr;
  }

  static HelperPool*& current() {
    static HelperPool* pool = nullptr;
    return pool;
  }

  // Takes the job's next chunk (under the lock); a job whose chunks are
  // all taken leaves the queue.
  std::size_t claim(detail::Job& job) {
    const std::size_t chunk = job.claimed++;
    unlinkIfDone(job);
    return chunk;
  }
  void unlinkIfDone(detail::Job& job) {
    if (job.claimed < job.count) return;
    for (auto it = pending_.begin(); it != pending_.end(); ++it)
      if (*it == &job) {
        pending_.erase(it);
        break;
      }
  }

  void serve() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (!stop_ && pending_.empty()) {
        const auto deadline = std::chrono::steady_clock::now() + kSpin;
        while (!stop_ && pending_.empty() && spinUntilChange(lock, epoch_, deadline)) {
        }
        if (!stop_ && pending_.empty())
          changed_.wait_for(lock, kIdle, [&] { return stop_ || !pending_.empty(); });
      }
      if (stop_ || pending_.empty()) break;  // released, or idle for kIdle
      --idle_;
      detail::Job& job = *pending_.front();
      const std::size_t chunk = claim(job);
      lock.unlock();
      avoidPosterCpu(job);
      job.run(job.context, chunk);
      lock.lock();
      ++idle_;
      if (++job.finished == job.count) signal();
    }
    --idle_;
    --helpers_;
    signal();
  }

  // Wakes the waiting threads; a spinning one sees the epoch change.
  // Always under the lock, so that a thread that finds the epoch as it was
  // there and then sleeps cannot miss a change.
  void signal() {
    epoch_.store(epoch_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
    changed_.notify_all();
  }

  // Before a thread sleeps on the condition, it watches the epoch with the
  // lock released, until it changes from `seen` (true) or the deadline
  // passes (false). The stages of one operation follow each other closely,
  // and a sleeping thread takes tens of microseconds to wake (as long as a
  // small mesh's stage); worse, the scheduler tends to wake it on the CPU
  // of the thread that woke it, and two threads then share one CPU for
  // milliseconds. Spinning, neither sleeps between the stages.
  bool spinUntilChange(std::unique_lock<std::mutex>& lock, std::uint64_t seen,
                       std::chrono::steady_clock::time_point deadline) {
    lock.unlock();
    bool changed = false;
    for (int i = 1;; ++i) {
      if (epoch_.load(std::memory_order_acquire) != seen) {
        changed = true;
        break;
      }
      relax();
      if (i % 64 == 0 && std::chrono::steady_clock::now() > deadline) break;
    }
    lock.lock();
    return changed;
  }
  static void relax() {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }

  // How long a waiting thread spins before it sleeps: longer than the
  // gaps between the parallel stages of one operation (and between the
  // operations of a script), short against anything a user waits for. A
  // helper that sleeps is woken on its waker's CPU and must move off it
  // again (see moveOffCpu). With 200 us, helpers slept within a split of two
  // small meshes; per-process medians of blobby + eight, ten processes
  // each: 0.98-1.43 ms with the move alone, 0.86-1.40 ms with the move and
  // 2 ms of spinning (1.01-2.75 ms with neither).
  static constexpr std::chrono::microseconds kSpin{2000};

  // How long a helper waits for work before it leaves: long enough to
  // span the gaps between one operation's stages, short against a user's
  // pause.
  static constexpr std::chrono::milliseconds kIdle{200};

  std::mutex mutex_;
  // A job was posted, a job's last chunk or a helper finished, or stop_ set.
  std::condition_variable changed_;
  std::atomic<std::uint64_t> epoch_{0};  // counts the changes, made under the lock
  std::deque<detail::Job*> pending_;
  std::size_t helpers_ = 0;  // started and not yet gone
  std::size_t idle_ = 0;     // of those, waiting for a chunk
  bool stop_ = false;
};

}  // namespace

namespace detail {

// Moves the calling thread off `cpu` onto another CPU it may run on, if
// there is one: its allowed set without that CPU for a moment (the kernel
// migrates it at once), then the whole set again (which does not move it
// back). Why: the scheduler wakes a sleeping helper on the CPU of the thread
// that woke it and leaves it there, next to that thread, while the other
// CPU idles; the two then take turns on one CPU, and a small operation takes
// two to four times as long (splits of blobby + eight, run after run: 0.8-0.9
// ms each in a process whose two threads ran on two CPUs, 1.6-3.8 ms in
// processes where they shared one).
bool moveOffCpu(int cpu) {
  cpu_set_t allowed;
  if (pthread_getaffinity_np(pthread_self(), sizeof allowed, &allowed) != 0) return false;
  if (!CPU_ISSET(cpu, &allowed) || CPU_COUNT(&allowed) < 2) return false;
  cpu_set_t others = allowed;
  CPU_CLR(cpu, &others);
  if (pthread_setaffinity_np(pthread_self(), sizeof others, &others) != 0) return false;
  pthread_setaffinity_np(pthread_self(), sizeof allowed, &allowed);
  return true;
}

void postJob(Job& job) {
  HelperPool::instance().post(job);
}

void finishJob(Job& job, bool runUntaken) {
  HelperPool::instance().finish(job, runUntaken);
}

void runJob(Job& job) {
  postJob(job);
  finishJob(job, true);
}

}  // namespace detail

namespace {

std::atomic<unsigned> chosenThreads{0};  // setThreadCount's, 0 when not set

// MESHMEND_THREADS as a count, or 0 when it is not set or not a whole
// number from 1 (then the CPUs decide).
unsigned threadsFromEnvironment() {
  const char* text = std::getenv("MESHMEND_THREADS");
  if (!text || !*text) return 0;
  char* end = nullptr;
  const unsigned long count = std::strtoul(text, &end, 10);
  if (*end != '\0' || count < 1 || count > 4096) return 0;
  return unsigned(count);
}

}  // namespace

unsigned defaultThreadCount() {
  static const unsigned count = [] {
    if (const unsigned fromEnvironment = threadsFromEnvironment()) return fromEnvironment;
    cpu_set_t allowed;
    if (sched_getaffinity(0, sizeof allowed, &allowed) == 0 && CPU_COUNT(&allowed) > 0)
      return unsigned(CPU_COUNT(&allowed));
    return std::max(1u, std::thread::hardware_concurrency());
  }();
  return count;
}

unsigned workerCount() {
  const unsigned chosen = chosenThreads.load(std::memory_order_relaxed);
  return chosen ? chosen : defaultThreadCount();
}

void setThreadCount(unsigned count) {
  const unsigned before = workerCount();
  chosenThreads.store(count, std::memory_order_relaxed);
  if (workerCount() < before) releaseHelperThreads();  // the next job starts what it may use
}

void releaseHelperThreads() {
  HelperPool::instance().release();
}

}  // namespace meshmend
