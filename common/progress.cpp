#include "common/progress.h"

#include "common/errors.h"

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

}  // namespace meshmend
