// parallel.h: every chunk runs exactly once, also when no thread can be
// started (a process at its thread limit, a container with few PIDs), in
// jobs posted from inside other jobs' chunks and in a child of fork(); the
// helpers serve job after job, on the CPUs the process may run on and off
// the CPU of the thread whose chunks they take; and the work that relies on it (hole
// filling re-points a moved mesh's faces in parallel) still finishes with
// the same result.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/base/parallel.h"
#include "common/repair/holes/holes.h"
#include "common/repair/split/split.h"
#include "tests/mesh_builders.h"

using namespace meshmend;
using namespace meshmend::testing;

namespace {
std::atomic<bool> refuseThreads{false};
std::atomic<int> threadsRefused{0};
}  // namespace

// This executable's pthread_create comes first in symbol lookup: while
// refuseThreads is set it fails as the C library does at the thread limit.
extern "C" int pthread_create(pthread_t* thread, const pthread_attr_t* attributes,
                              void* (*start)(void*), void* argument) {
  using Create = int (*)(pthread_t*, const pthread_attr_t*, void* (*)(void*), void*);
  static const Create real = reinterpret_cast<Create>(dlsym(RTLD_NEXT, "pthread_create"));
  if (refuseThreads) {
    ++threadsRefused;
    return EAGAIN;
  }
  return real(thread, attributes, start, argument);
}

namespace {
// Helpers kept from earlier work are released first: the work under test
// must ask for threads, and be refused.
struct NoThreads {
  NoThreads() {
    releaseHelperThreads();
    refuseThreads = true, threadsRefused = 0;
  }
  ~NoThreads() { refuseThreads = false; }
};

Mesh sphereWithCap() {
  return withHole(icosphere(6), [](const Point3& c) { return c[2] > 0.75; });
}
}  // namespace

TEST(ParallelChunks, EveryChunkRunsOnceWithThreads) {
  std::vector<int> visits(100000, 0);
  parallelChunks(visits.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) ++visits[i];
  });
  for (int v : visits) ASSERT_EQ(v, 1);
}

TEST(ParallelChunks, EveryChunkRunsOnceWhenNoThreadStarts) {
  NoThreads none;
  std::vector<int> visits(100000, 0);
  EXPECT_NO_THROW(parallelChunks(visits.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) ++visits[i];
  }));
  // The refusal was met, not avoided (with one core no thread is asked for).
  EXPECT_EQ(threadsRefused.load() > 0, workerCount() > 1);
  for (int v : visits) ASSERT_EQ(v, 1);
}

TEST(ParallelChunks, JobsPostedFromChunksFinish) {
  // Every chunk of the outer job posts a job of its own and a task
  // alongside: with all helpers busy, their posters run them.
  std::vector<std::atomic<int>> visits(64 * 1000);
  std::atomic<int> tasks{0};
  parallelChunks(
      64,
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) {
          TaskAlongside task([&] { ++tasks; });
          parallelChunks(
              1000,
              [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t k = b; k < e; ++k) ++visits[i * 1000 + k];
              },
              100);
          task.wait();
        }
      },
      1);
  EXPECT_EQ(tasks.load(), 64);
  for (const auto& v : visits) ASSERT_EQ(v.load(), 1);
}

TEST(ParallelChunks, AWaitingPosterHelpsWithJobsPostedByHelpers) {
  // The outer job's chunk on a helper posts an inner job of slow chunks
  // while the caller, done with its own chunk, waits: it takes one of them.
  const auto caller = std::this_thread::get_id();
  std::mutex mutex;
  std::set<std::thread::id> innerThreads;
  bool innerRan = false;
  for (int attempt = 0; attempt < 50 && !innerRan; ++attempt)
    parallelChunks(
        2,
        [&](std::size_t, std::size_t, unsigned) {
          if (std::this_thread::get_id() == caller) {  // leaves the other chunk to a helper
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            return;
          }
          parallelChunks(
              2,
              [&](std::size_t, std::size_t, unsigned) {
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
                std::lock_guard<std::mutex> lock(mutex);
                innerThreads.insert(std::this_thread::get_id());
              },
              1);
          innerRan = true;
        },
        1);
  if (workerCount() > 1) {
    ASSERT_TRUE(innerRan) << "no outer chunk ran on a helper in 50 jobs";
    EXPECT_EQ(innerThreads.size(), 2u);
    EXPECT_EQ(innerThreads.count(caller), 1u);
  } else {
    EXPECT_FALSE(innerRan);  // one core: the caller runs every chunk
  }
}

TEST(ParallelChunks, AnErrorOfOneChunkIsRethrownOnceAllHaveRun) {
  std::vector<std::atomic<int>> visits(workerCount());
  EXPECT_THROW(parallelChunks(
                   workerCount(),
                   [&](std::size_t begin, std::size_t, unsigned worker) {
                     ++visits[begin];
                     if (worker == 0) throw std::runtime_error("chunk 0");
                   },
                   1),
               std::runtime_error);
  for (const auto& v : visits) EXPECT_EQ(v.load(), 1);
}

TEST(TaskAlongside, RethrowsOnWaitAndIsDroppedWhenNotWaitedFor) {
  TaskAlongside failing([] { throw std::runtime_error("task"); });
  EXPECT_THROW(failing.wait(), std::runtime_error);
  // No helper to take it: left unwaited, the task never runs.
  std::atomic<int> runs{0};
  {
    NoThreads none;
    TaskAlongside dropped([&] { ++runs; });
  }
  EXPECT_EQ(runs.load(), 0);
  // With no helper, wait() runs it here, once.
  {
    NoThreads none;
    TaskAlongside waited([&] { ++runs; });
    waited.wait();
    waited.wait();
  }
  EXPECT_EQ(runs.load(), 1);
}

TEST(ParallelChunks, HelpersServeJobAfterJob) {
  // Chunks run on the caller and on helpers; a helper that serves job
  // after job counts more than one in its thread's counter (a thread per
  // job would count one each).
  static thread_local int chunksHere = 0;
  std::atomic<int> mostOnAHelper{0};
  const auto caller = std::this_thread::get_id();
  for (int job = 0; job < 20; ++job)
    parallelChunks(
        workerCount(),
        [&](std::size_t, std::size_t, unsigned) {
          std::this_thread::sleep_for(std::chrono::milliseconds(2));  // long enough to be shared
          if (std::this_thread::get_id() == caller) return;
          const int here = ++chunksHere;
          for (int m = mostOnAHelper; m < here && !mostOnAHelper.compare_exchange_weak(m, here);) {
          }
        },
        1);
  if (workerCount() > 1)
    EXPECT_GE(mostOnAHelper.load(), 2);
  else
    EXPECT_EQ(mostOnAHelper.load(), 0);  // one core: the caller runs every chunk
}

namespace {
cpu_set_t allowedCpus() {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  EXPECT_EQ(sched_getaffinity(0, sizeof allowed, &allowed), 0);
  return allowed;
}
}  // namespace

TEST(ParallelChunks, WorkerCountIsTheCpusTheProcessMayRunOn) {
  if (std::getenv("MESHMEND_THREADS")) GTEST_SKIP() << "MESHMEND_THREADS is set";
  cpu_set_t allowed = allowedCpus();
  EXPECT_EQ(workerCount(), unsigned(CPU_COUNT(&allowed)));
}

// setThreadCount caps the threads of every job that follows: one thread
// runs every chunk (on the caller) and a task alongside on the caller when
// waited for; 0 goes back to the default.
TEST(ThreadCount, OneThreadRunsEverythingOnTheCaller) {
  setThreadCount(1);
  EXPECT_EQ(workerCount(), 1u);
  std::mutex mutex;
  std::set<std::thread::id> threads;
  int chunks = 0;
  parallelChunks(
      1 << 20,
      [&](std::size_t, std::size_t, unsigned worker) {
        std::lock_guard<std::mutex> lock(mutex);
        EXPECT_EQ(worker, 0u);
        ++chunks;
        threads.insert(std::this_thread::get_id());
      },
      1);
  EXPECT_EQ(chunks, 1);
  EXPECT_EQ(threads, std::set<std::thread::id>{std::this_thread::get_id()});
  std::thread::id ranOn;
  TaskAlongside task([&] { ranOn = std::this_thread::get_id(); });
  task.wait();
  EXPECT_EQ(ranOn, std::this_thread::get_id());
  setThreadCount(0);
  EXPECT_EQ(workerCount(), defaultThreadCount());
  setThreadCount(3);
  EXPECT_EQ(workerCount(), 3u);
  setThreadCount(0);
}

// Run in a child process started with MESHMEND_THREADS (and the count it
// should give in MESHMEND_THREADS_EXPECTED); in this process it checks
// nothing when they are not set.
TEST(ThreadCount, ChildSeesTheEnvironmentVariable) {
  const char* expected = std::getenv("MESHMEND_THREADS_EXPECTED");
  if (!expected) GTEST_SKIP() << "run by EnvironmentVariableSetsTheDefault";
  EXPECT_EQ(defaultThreadCount(), unsigned(std::atoi(expected)));
  EXPECT_EQ(workerCount(), unsigned(std::atoi(expected)));
}

// MESHMEND_THREADS sets the default count of a process; a value that is
// not a whole number from 1 leaves the CPUs' count.
TEST(ThreadCount, EnvironmentVariableSetsTheDefault) {
  const cpu_set_t allowed = allowedCpus();
  const std::string cpus = std::to_string(CPU_COUNT(&allowed));
  for (const auto& [value, expected] : std::vector<std::pair<std::string, std::string>>{
           {"1", "1"}, {"3", "3"}, {"0", cpus}, {"two", cpus}, {"-1", cpus}}) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      setenv("MESHMEND_THREADS", value.c_str(), 1);
      setenv("MESHMEND_THREADS_EXPECTED", expected.c_str(), 1);
      execl("/proc/self/exe", "parallel_test",
            "--gtest_filter=ThreadCount.ChildSeesTheEnvironmentVariable",
            static_cast<char*>(nullptr));
      _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << "MESHMEND_THREADS=" << value << ": the child failed (status " << status << ")";
  }
}

// moveOffCpu leaves the CPU it is given and keeps the set the thread may run
// on; with no other CPU to go to it says so and stays.
TEST(ParallelChunks, MoveOffCpuLeavesTheCpuAndKeepsTheAllowedSet) {
  std::thread([] {
    const cpu_set_t allowed = allowedCpus();
    for (int attempt = 0; attempt < 20; ++attempt) {
      const int cpu = sched_getcpu();
      ASSERT_GE(cpu, 0);
      const bool moved = detail::moveOffCpu(cpu);
      EXPECT_EQ(moved, CPU_COUNT(&allowed) > 1);
      if (moved) {
        EXPECT_NE(sched_getcpu(), cpu);  // not moved back by the restored set
      }
      cpu_set_t now = allowedCpus();
      EXPECT_TRUE(CPU_EQUAL(&now, &allowed));
    }
    // Pinned to one CPU, there is nowhere to go.
    cpu_set_t one;
    CPU_ZERO(&one);
    const int cpu = sched_getcpu();
    CPU_SET(cpu, &one);
    ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof one, &one), 0);
    EXPECT_FALSE(detail::moveOffCpu(cpu));
    EXPECT_EQ(sched_getcpu(), cpu);
  }).join();
}

// A helper never starts a chunk on the CPU its poster was on when it posted:
// the poster, pinned to one CPU, posts jobs whose chunks take long enough
// for a helper to take one; each chunk notes where it ran.
TEST(ParallelChunks, HelpersRunChunksOffThePostersCpu) {
  if (workerCount() < 2) {
    EXPECT_EQ(workerCount(), 1u);  // one CPU: the caller runs every chunk (HelpersServeJobAfterJob)
    return;
  }
  parallelChunks(
      2, [](std::size_t, std::size_t, unsigned) {}, 1);  // helpers with every CPU
  std::thread([] {
    const int posterCpu = sched_getcpu();
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(posterCpu, &one);
    ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof one, &one), 0);
    const auto poster = std::this_thread::get_id();
    std::atomic<int> onHelpers{0}, onPostersCpu{0};
    for (int job = 0; job < 20; ++job) {
      // Let the helpers fall asleep now and then: a woken helper may start
      // out next to its waker, a spinning one may be put there.
      if (job % 4 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      parallelChunks(
          2,
          [&](std::size_t, std::size_t, unsigned) {
            // Where the chunk starts: later, a busy machine's load balancing
            // may move the helper anywhere.
            const int cpu = sched_getcpu();
            const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(2);
            while (std::chrono::steady_clock::now() < until) {
            }
            if (std::this_thread::get_id() == poster) return;
            ++onHelpers;
            if (cpu == posterCpu) ++onPostersCpu;
          },
          1);
    }
    EXPECT_GT(onHelpers.load(), 0);
    EXPECT_EQ(onPostersCpu.load(), 0);
  }).join();
}

namespace {
// Waits (up to five seconds: a sanitizer's thread start is slow) until
// `done` holds.
template <class Condition>
bool waitFor(Condition done) {
  const auto start = std::chrono::steady_clock::now();
  while (!done()) {
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(5)) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// What a child of fork() checks, as its exit code: its jobs run every
// chunk once, a task alongside runs, and it has helpers of its own (a
// chunk on the caller waits until a helper has taken another).
int checkJobsInForkedChild() {
  std::vector<int> visits(100000, 0);
  parallelChunks(visits.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) ++visits[i];
  });
  bool ran = false;
  TaskAlongside task([&] { ran = true; });
  task.wait();
  for (int v : visits)
    if (v != 1) return 2;
  if (!ran) return 3;
  const auto caller = std::this_thread::get_id();
  std::atomic<int> elsewhere{0};
  parallelChunks(
      workerCount(),
      [&](std::size_t, std::size_t, unsigned) {
        if (std::this_thread::get_id() != caller)
          ++elsewhere;
        else
          waitFor([&] { return elsewhere > 0; });
      },
      1);
  return (elsewhere > 0) == (workerCount() > 1) ? 0 : 4;
}
}  // namespace

// The parent forks from inside a job while its helpers are busy with the
// job's other chunks: the child inherits a pool that counts them, though
// they are not there. The helpers wait in the test's own code, where they
// hold no lock (a sanitizer's allocator, unlike the C library's, is not
// made safe across fork: a helper allocating at that moment would leave
// its lock held in the child).
TEST(ParallelChunks, AChildOfForkRunsJobsWithoutItsParentsHelpers) {
  const auto caller = std::this_thread::get_id();
  const unsigned helpers = workerCount() - 1;
  std::atomic<unsigned> helpersInside{0};
  std::atomic<bool> forked{false};
  bool helpersWereInside = false;
  pid_t child = -1;
  int status = 0;
  parallelChunks(
      workerCount(),
      [&](std::size_t, std::size_t, unsigned) {
        if (std::this_thread::get_id() != caller) {
          ++helpersInside;
          waitFor([&] { return forked.load(); });
          return;
        }
        if (forked) return;  // the caller took a second chunk
        helpersWereInside = waitFor([&] { return helpersInside == helpers; });
        child = fork();
        if (child == 0) {
          alarm(60);  // a hang fails the test instead of stopping it
          _exit(checkJobsInForkedChild());
        }
        forked = true;
        if (child > 0 && waitpid(child, &status, 0) != child) child = -1;
      },
      1);
  EXPECT_TRUE(helpersWereInside) << "the parent's helpers did not take their chunks";
  ASSERT_GT(child, 0) << "fork or waitpid failed";
  ASSERT_TRUE(WIFEXITED(status)) << "the child was stopped by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// The mesh in arrays of exactly its size (a built mesh keeps room to grow):
// vcglib's allocator on an empty mesh, as an importer fills one.
void exactSize(const Mesh& from, Mesh& m) {
  const std::vector<Point3> p = positionsOf(from);
  const std::vector<Triangle> t = trianglesOf(from);
  vcg::tri::Allocator<Mesh>::AddVertices(m, p.size());
  for (std::size_t v = 0; v < p.size(); ++v) m.vert[v].P() = p[v];
  vcg::tri::Allocator<Mesh>::AddFaces(m, t.size());
  for (std::size_t f = 0; f < t.size(); ++f)
    for (int k = 0; k < 3; ++k) m.face[f].V(k) = &m.vert[std::size_t(t[f][k])];
}

TEST(ParallelChunks, HoleFillingWithoutThreadsGivesTheSameMesh) {
  // Exact-size arrays, so that the write-back moves the vertices and
  // re-points every face (the step that must not be left half done).
  Mesh withThreads, withoutThreads;
  exactSize(sphereWithCap(), withThreads);
  const std::size_t inputFaces = withThreads.face.size();
  ASSERT_GT(inputFaces, 20000u);  // large enough for the parallel paths
  ASSERT_EQ(withThreads.vert.capacity(), withThreads.vert.size());
  exactSize(sphereWithCap(), withoutThreads);
  const HoleFillResult a = fillHoles(withThreads);
  HoleFillResult b;
  {
    NoThreads none;
    EXPECT_NO_THROW(b = fillHoles(withoutThreads));
    if (workerCount() > 1) {
      EXPECT_GT(threadsRefused.load(), 0);
    }
  }
  ASSERT_EQ(a.holes_filled, 1u);
  ASSERT_EQ(b.holes_filled, 1u);
  ASSERT_EQ(positionsOf(withoutThreads), positionsOf(withThreads));
  ASSERT_EQ(trianglesOf(withoutThreads), trianglesOf(withThreads));
  for (const Face& f : withoutThreads.face)
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(f.cV(k), withoutThreads.vert.data());
      ASSERT_LT(f.cV(k), withoutThreads.vert.data() + withoutThreads.vert.size());
    }
}

TEST(ParallelChunks, SplitWithoutThreadsGivesTheSameMeshes) {
  // Large enough for the separate meshes to be built on a second thread.
  const Mesh a = icosphere(6), b = icosphere(6, 1, {1, 0.1, 0.05});
  const SplitResult withThreads = splitAlongIntersections({&a, &b});
  SplitResult withoutThreads;
  {
    NoThreads none;
    EXPECT_NO_THROW(withoutThreads = splitAlongIntersections({&a, &b}));
    if (workerCount() > 1) {
      EXPECT_GT(threadsRefused.load(), 0);
    }
  }
  ASSERT_GT(withThreads.faces_split, 0u);
  ASSERT_EQ(withoutThreads.meshes.size(), 2u);
  for (std::size_t m = 0; m < 2; ++m) {
    EXPECT_EQ(positionsOf(withoutThreads.meshes[m]), positionsOf(withThreads.meshes[m]));
    EXPECT_EQ(trianglesOf(withoutThreads.meshes[m]), trianglesOf(withThreads.meshes[m]));
    EXPECT_EQ(withoutThreads.curve_edges[m], withThreads.curve_edges[m]);
  }
  EXPECT_EQ(positionsOf(withoutThreads.merged), positionsOf(withThreads.merged));
  EXPECT_EQ(trianglesOf(withoutThreads.merged), trianglesOf(withThreads.merged));
}
