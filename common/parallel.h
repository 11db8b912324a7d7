// Minimal data parallelism over index ranges with std::thread.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace meshmend {

// Number of worker threads used by parallelChunks (at least 1).
inline unsigned workerCount() {
  return std::max(1u, std::thread::hardware_concurrency());
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
  std::vector<std::thread> threads;
  threads.reserve(workers - 1);
  for (std::size_t w = 1; w < workers; ++w) threads.emplace_back(run, w);
  run(0);
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace meshmend
