// Progress reporting of long operations.
#pragma once

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

}  // namespace meshmend
