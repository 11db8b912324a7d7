// Progress reporting of long operations.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>

namespace meshmend {

// Called with a percentage (0..100) and the name of the current stage.
// Returning false asks the operation to stop (it throws CancelledError).
using Progress = std::function<bool(int percent, const char* stage)>;

// Reports progress if a callback is set; throws CancelledError when asked to stop.
void reportProgress(const Progress& progress, int percent, const char* stage);

// `outer` for a part of the work that takes its range [from, to]: the
// part's own 0..100 mapped onto that range, so that the percentages a user
// sees only grow. Empty when `outer` is.
Progress progressWithin(const Progress& outer, int from, int to);

// Progress from inside a loop of `total` steps that covers `from` to `to`
// percent of an operation: step() is cheap enough for every iteration and
// calls the callback (so that the user can cancel) when the percentage
// changes or a quarter of a second has passed since the last call. For the
// thread that owns the callback only (MeshLab's is not thread-safe).
class ProgressSpan {
 public:
  ProgressSpan(const Progress& progress, int from, int to, std::size_t total, const char* stage);
  // `done` of the `total` steps are finished.
  void step(std::size_t done) {
    if (progress_ && (done * span_ / total_ != last_ || ++calls_ % 64 == 0)) report(done);
  }

 private:
  void report(std::size_t done);
  const Progress& progress_;
  int from_;
  std::size_t span_, total_;
  const char* stage_;
  std::size_t last_ = 0, calls_ = 0;
  std::chrono::steady_clock::time_point reported_;
};

}  // namespace meshmend
