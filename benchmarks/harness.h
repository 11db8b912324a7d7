// The benchmark harness every capability's runner uses: each method runs in
// a forked child (so that its peak memory is its own and a crash of a peer is
// reported, not fatal), repeated, and reports its median time.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common/json.h"

namespace meshmend::bench {

struct Method {
  std::string name;  // e.g. "meshmend_cross", "cgal_self_intersections"
  std::string role;  // "ours", "peer" or "alternative"
  // Prepares the inputs (untimed) and returns the timed work, which returns
  // the method's result count (pairs found, faces added, ...).
  std::function<std::function<long()>()> prepare;
};

struct Measurement {
  std::string name, role;
  bool ok = false;
  std::string error;
  long result = 0;
  std::vector<double> times_ms;
  double median_ms = 0, min_ms = 0;
  double peak_rss_mb = 0;      // the child's peak resident memory
  double baseline_rss_mb = 0;  // after preparing, before the timed work
};

// Runs `method` `repeat` times in a child process (time limit in seconds).
Measurement measure(const Method& method, int repeat, int timeLimitSeconds = 600);

JsonObject toJson(const Measurement& m);

}  // namespace meshmend::bench
