#include "benchmarks/harness.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <sstream>

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace meshmend::bench {

namespace {

rusage usage() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u;
}

double maxRssMb() {
  return double(usage().ru_maxrss) / 1024.0;  // Linux: kilobytes
}

long minorFaults() {
  return usage().ru_minflt;
}

// Resets the kernel's record of the peak resident memory to what is
// resident now (Linux 4.0 and later); false where it is refused.
bool resetPeak() {
  FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

// The peak resident memory since the last reset (VmHWM), in MB; 0 if unknown.
double peakSinceResetMb() {
  FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  double kb = 0;
  while (std::fgets(line, sizeof line, f))
    if (std::sscanf(line, "VmHWM: %lf kB", &kb) == 1) break;
  std::fclose(f);
  return kb / 1024.0;
}

}  // namespace

Measurement measure(const Method& method, int repeat, int timeLimitSeconds) {
  Measurement m;
  m.name = method.name;
  m.role = method.role;
  int fds[2];
  if (pipe(fds) != 0) {
    m.error = "pipe failed";
    return m;
  }
  const pid_t pid = fork();
  if (pid == 0) {  // child: prepare, run, write "result baseline peak faults t1 t2 ..."
    close(fds[0]);
    alarm(unsigned(timeLimitSeconds));
    std::ostringstream out;
    try {
      std::function<long()> work = method.prepare();
      const double baseline = maxRssMb();
      const bool reset = resetPeak();
      long result = 0;
      std::vector<double> times;
      std::vector<long> faults;  // per run
      for (int i = 0; i < repeat; ++i) {
        const long faultsBefore = minorFaults();
        const auto t0 = std::chrono::steady_clock::now();
        result = work();
        times.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        faults.push_back(minorFaults() - faultsBefore);
      }
      std::sort(faults.begin(), faults.end());
      const double peak = reset ? peakSinceResetMb() : 0;
      out << "ok " << result << ' ' << baseline << ' ' << (peak > 0 ? peak : maxRssMb()) << ' '
          << (faults.empty() ? 0 : faults[faults.size() / 2]);
      for (double t : times) out << ' ' << t;
    } catch (const std::exception& e) {
      out << "error " << e.what();
    }
    const std::string s = out.str();
    ssize_t written = write(fds[1], s.data(), s.size());
    (void)written;
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string text;
  char buffer[4096];
  for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) > 0;)
    text.append(buffer, std::size_t(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFSIGNALED(status)) {
    m.error = WTERMSIG(status) == SIGALRM
                  ? "time limit of " + std::to_string(timeLimitSeconds) + " s"
                  : std::string("crashed: ") + strsignal(WTERMSIG(status));
    return m;
  }
  std::istringstream in(text);
  std::string word;
  in >> word;
  if (word != "ok") {
    std::getline(in, m.error);
    if (m.error.empty()) m.error = "no result";
    return m;
  }
  m.ok = true;
  in >> m.result >> m.baseline_rss_mb >> m.peak_rss_mb >> m.page_faults_per_run;
  for (double t; in >> t;) m.times_ms.push_back(t);
  std::vector<double> sorted = m.times_ms;
  std::sort(sorted.begin(), sorted.end());
  m.median_ms = sorted.empty() ? 0 : sorted[sorted.size() / 2];
  m.min_ms = sorted.empty() ? 0 : sorted.front();
  return m;
}

JsonObject toJson(const Measurement& m) {
  JsonObject j;
  j.set("method", m.name).set("role", m.role).set("ok", m.ok);
  if (!m.ok) return j.set("error", m.error);
  return j.set("result", long(m.result))
      .set("median_ms", m.median_ms)
      .set("min_ms", m.min_ms)
      .set("times_ms", m.times_ms)
      .set("peak_rss_mb", m.peak_rss_mb)
      .set("baseline_rss_mb", m.baseline_rss_mb)
      .set("page_faults_per_run", m.page_faults_per_run);
}

void warmAllocator() {
  // Setting the thresholds turns glibc's dynamic rule off, at the values it
  // would have reached (DEFAULT_MMAP_THRESHOLD_MAX, twice that for trimming).
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
}

CommandLine::CommandLine(int argc, char** argv, std::set<std::string> flags)
    : flags_(std::move(flags)) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0)
      files_.push_back(arg);
    else if (flags_.count(arg))
      given_.insert(arg);
    else if (i + 1 < argc)
      values_[arg] = argv[++i];
    else
      malformed_ = true;
  }
}

bool CommandLine::flag(const std::string& name) {
  read_.insert(name);
  return given_.count(name) > 0;
}

int CommandLine::integer(const std::string& name, int fallback) {
  return int(std::lround(real(name, fallback)));
}

double CommandLine::real(const std::string& name, double fallback) {
  const std::string t = text(name, "");
  return t.empty() ? fallback : std::atof(t.c_str());
}

std::string CommandLine::text(const std::string& name, const std::string& fallback) {
  read_.insert(name);
  const auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

bool CommandLine::complete(std::size_t minFiles, std::size_t maxFiles, const char* usage) const {
  bool ok = !malformed_ && files_.size() >= minFiles && files_.size() <= maxFiles;
  for (const auto& [name, value] : values_) ok &= read_.count(name) > 0;
  if (!ok) std::fprintf(stderr, "usage: %s\n", usage);
  return ok;
}

}  // namespace meshmend::bench
