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
  std::vector<std::thread> threads;
  std::vector<std::exception_ptr> errors(workers);
  for (std::size_t w = 0; w < workers; ++w)
    threads.emplace_back([&, w] {
      try {
        body(n * w / workers, n * (w + 1) / workers, unsigned(w));
      } catch (...) {
        errors[w] = std::current_exception();
      }
    });
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace meshmend
