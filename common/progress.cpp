#include "common/progress.h"

#include "common/errors.h"

namespace meshmend {

void reportProgress(const Progress& progress, int percent, const char* stage) {
  if (progress && !progress(percent, stage)) throw CancelledError();
}

}  // namespace meshmend
