// The benchmark harness every capability's runner uses: each method runs in
// a forked child (so that its peak memory is its own and a crash of a peer is
// reported, not fatal), repeated, and reports its median time.
#pragma once

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/base/json.h"

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
  // The child's peak resident memory while the timed runs ran (its
  // prepared inputs included): the kernel's peak is reset once the inputs
  // are made (/proc/self/clear_refs), so that reading the input files does
  // not count; where that is refused, the process's peak since it started.
  double peak_rss_mb = 0;
  double baseline_rss_mb = 0;  // after preparing, before the timed work
  // Pages a timed run touched for the first time (minor page faults; the
  // median run): after the first runs, memory the allocator had given back
  // to the system and took again. On a virtual machine each costs
  // microseconds.
  double page_faults_per_run = 0;
};

// Runs `method` `repeat` times in a child process (time limit in seconds).
Measurement measure(const Method& method, int repeat, int timeLimitSeconds = 600);

// Puts glibc's malloc, in this process and the children measure() forks
// from it, in the state its own dynamic rule reaches in a process that has
// freed a block of 32 MiB or more (a host that has loaded and dropped a mesh
// of a few hundred thousand faces): blocks up to 32 MiB come from the heap,
// and up to 64 MiB of freed memory at its top stays with the process.
// Otherwise a fresh process keeps the thresholds of its largest block freed
// so far, and a method whose result just exceeds them hands its memory back
// to the system after every run and faults it in again in the next one.
void warmAllocator();

JsonObject toJson(const Measurement& m);

// A runner's command line: "--name value" options, the "--flag"s declared
// as such, and the files, in any order. Each runner reads what it takes;
// complete() then says whether that was all (no option left unread, the
// number of files right) and prints the usage line when it was not.
class CommandLine {
 public:
  CommandLine(int argc, char** argv, std::set<std::string> flags = {});
  bool flag(const std::string& name);
  int integer(const std::string& name, int fallback);
  double real(const std::string& name, double fallback);
  std::string text(const std::string& name, const std::string& fallback);
  const std::vector<std::string>& files() const { return files_; }
  bool complete(std::size_t minFiles, std::size_t maxFiles, const char* usage) const;

 private:
  std::set<std::string> flags_, given_, read_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> files_;
  bool malformed_ = false;  // an option without its value
};

}  // namespace meshmend::bench
