// Minimal data parallelism over index ranges with std::thread.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <functional>
#include <system_error>
#include <thread>
#include <vector>

namespace meshmend {

// Number of worker threads used by parallelChunks (at least 1).
// hardware_concurrency reads /sys on every call (two file opens), which
// costs more than a small job's work: asked once.
inline unsigned workerCount() {
  static const unsigned count = std::max(1u, std::thread::hardware_concurrency());
  return count;
}

// Splits [0, n) into one contiguous chunk per worker and calls
// body(begin, end, worker) on each, in parallel; small ranges run inline.
// The first exception thrown by a worker is rethrown after all have joined.
template <class Body>
void parallelChunks(std::size_t n, Body&& body, std::size_t minimumPerWorker = 4096) {
  const std::size_t workers = std::max<std::size_t>(
      1, std::min<std::size_t>(workerCount(), n / std::max<std::size_t>(1, minimumPerWorker)));
  if (workers == 1) {
    body(std::size_t(0), n, 0u);
    return;
  }
  std::vector<std::exception_ptr> errors(workers);
  auto run = [&](std::size_t w) {
    try {
      body(n * w / workers, n * (w + 1) / workers, unsigned(w));
    } catch (...) {
      errors[w] = std::current_exception();
    }
  };
  // The calling thread takes the first chunk: one thread fewer to start.
  // When no thread can be started (std::system_error) or the list of them
  // cannot grow, the chunks left run here too: every chunk runs exactly
  // once, so callers that must finish a job (re-pointing a moved mesh's
  // faces) can rely on it, and no started thread is left unjoined.
  std::vector<std::thread> threads;
  std::size_t started = 1;
  try {
    threads.reserve(workers - 1);
    for (; started < workers; ++started) threads.emplace_back(run, started);
  } catch (...) {
  }
  run(0);
  for (std::size_t w = started; w < workers; ++w) run(w);
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

// Runs a task on a second thread while the caller works on, or, when no
// thread can be started, on the calling thread once it is waited for: the
// task runs exactly once either way (if waited for). The destructor joins
// a started thread (an error on the caller's side leaves nothing running).
class TaskAlongside {
 public:
  explicit TaskAlongside(std::function<void()> task) : task_(std::move(task)) {
    try {
      thread_ = std::thread(task_);
      task_ = nullptr;
    } catch (const std::system_error&) {  // no thread to spare: wait() runs it
    }
  }
  TaskAlongside(const TaskAlongside&) = delete;
  TaskAlongside& operator=(const TaskAlongside&) = delete;
  ~TaskAlongside() {
    if (thread_.joinable()) thread_.join();
  }
  void wait() {
    if (thread_.joinable()) {
      thread_.join();
    } else if (task_) {
      std::function<void()> task = std::move(task_);
      task_ = nullptr;
      task();
    }
  }

 private:
  std::function<void()> task_;
  std::thread thread_;
};

}  // namespace meshmend
