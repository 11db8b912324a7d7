// parallel.h: every chunk runs exactly once, also when no thread can be
// started (a process at its thread limit, a container with few PIDs), and
// the work that relies on it (hole filling re-points a moved mesh's faces
// in parallel) still finishes with the same result.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <cerrno>
#include <vector>

#include "common/holes.h"
#include "common/parallel.h"
#include "common/split.h"
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
struct NoThreads {
  NoThreads() { refuseThreads = true, threadsRefused = 0; }
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

TEST(ParallelChunks, HoleFillingWithoutThreadsGivesTheSameMesh) {
  Mesh withThreads = sphereWithCap();
  const std::size_t inputFaces = withThreads.face.size();
  ASSERT_GT(inputFaces, 20000u);  // large enough for the parallel paths
  Mesh withoutThreads = sphereWithCap();
  // Exact-size arrays, so that the write-back moves the vertices and
  // re-points every face (the step that must not be left half done).
  withThreads.vert.shrink_to_fit(), withThreads.face.shrink_to_fit();
  withoutThreads.vert.shrink_to_fit(), withoutThreads.face.shrink_to_fit();
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
