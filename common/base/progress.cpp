#include "common/base/progress.h"

#include <algorithm>

#include "common/base/errors.h"

namespace meshmend {

void reportProgress(const Progress& progress, int percent, const char* stage) {
  if (progress && !progress(percent, stage)) throw CancelledError();
}

Progress progressWithin(const Progress& outer, int from, int to) {
  if (!outer) return {};
  return [outer, from, to](int percent, const char* stage) {
    return outer(from + (to - from) * percent / 100, stage);
  };
}

ProgressSpan::ProgressSpan(const Progress& progress, int from, int to, std::size_t total,
                           const char* stage)
    : progress_(progress),
      from_(from),
      span_(std::size_t(std::max(0, to - from))),
      total_(std::max<std::size_t>(total, 1)),
      stage_(stage),
      reported_(std::chrono::steady_clock::now()) {
  reportProgress(progress_, from_, stage_);
}

void ProgressSpan::report(std::size_t done) {
  const std::size_t part = std::min(done, total_) * span_ / total_;
  const auto now = std::chrono::steady_clock::now();
  if (part == last_ && now - reported_ < std::chrono::milliseconds(250)) return;
  last_ = part;
  reported_ = now;
  reportProgress(progress_, from_ + int(part), stage_);
}

}  // namespace meshmend
