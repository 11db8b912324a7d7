// Replays through the fuzz targets' bodies (fuzz/targets.cpp) every input
// that once made a target fail (fuzz/regressions/<target>/), and a small
// input of each target's form built here: each must now pass its target's
// checks (no crash, only the core's typed errors, the checked properties).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz/fuzz_input.h"

#ifndef MESHMEND_FUZZ_REGRESSIONS
#error "MESHMEND_FUZZ_REGRESSIONS (the fuzz/regressions folder) must be defined"
#endif

namespace fs = std::filesystem;
using meshmend::fuzz::Finding;
using meshmend::fuzz::targets;

namespace {

std::vector<std::uint8_t> bytesOf(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void run(const meshmend::fuzz::Target& t, const std::vector<std::uint8_t>& bytes,
         const std::string& what) {
  try {
    t.body(bytes.data(), bytes.size());
  } catch (const Finding& e) {
    ADD_FAILURE() << t.name << " on " << what << ": " << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << t.name << " on " << what << ": unexpected exception: " << e.what();
  }
}

// A unit box on the grid encoding (fuzz/fuzz_input.h), two copies overlapping.
std::vector<std::uint8_t> twoBoxes() {
  std::vector<std::uint8_t> b{0, 0, 128, 16, 0};
  for (int copy = 0; copy < 2; ++copy)
    for (int i = 0; i < 8; ++i)
      for (int k = 0; k < 3; ++k) b.push_back(std::uint8_t(((i >> k) & 1) * 4 + copy * 2));
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (int copy = 0; copy < 2; ++copy)
    for (const auto& f : faces)
      for (int v : f) b.push_back(std::uint8_t(v + 8 * copy)), b.push_back(0);
  return b;
}

}  // namespace

TEST(FuzzRegressions, EveryRecordedInputPasses) {
  std::size_t replayed = 0;
  for (const auto& t : targets()) {
    const fs::path folder = fs::path(MESHMEND_FUZZ_REGRESSIONS) / t.name;
    if (!fs::is_directory(folder)) continue;
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (!entry.is_regular_file()) continue;
      run(t, bytesOf(entry.path()), entry.path().filename().string());
      ++replayed;
    }
  }
  std::printf("replayed %zu recorded inputs\n", replayed);
}

TEST(FuzzRegressions, EveryTargetTakesAnInputOfItsForm) {
  const std::vector<std::uint8_t> boxes = twoBoxes();
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf -3 -2 -1\n";
  for (const auto& t : targets()) {
    if (std::strcmp(t.name, "obj_reader") == 0) {
      run(t, std::vector<std::uint8_t>(obj.begin(), obj.end()), "a small OBJ");
    } else {
      run(t, boxes, "two boxes");
      std::vector<std::uint8_t> led{0};  // targets that read an options byte first
      led.insert(led.end(), boxes.begin(), boxes.end());
      run(t, led, "an option byte and two boxes");
    }
    run(t, {}, "no bytes");
  }
}
