// huge_pages.h: the helpers are reserve, resize and assign (sizes, values,
// capacities, small arrays alike), and where the kernel gives transparent
// huge pages on request, a large array made by them is in huge pages;
// advising ranges that are too small, unaligned or empty is harmless.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/base/huge_pages.h"

using namespace meshmend;

namespace {

// The mode in /sys/kernel/mm/transparent_hugepage/enabled ("always",
// "madvise" or "never"), or "" when the kernel has no huge pages.
std::string hugePageMode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string text;
  std::getline(in, text);
  const std::size_t open = text.find('['), close = text.find(']');
  return open == std::string::npos || close == std::string::npos
             ? ""
             : text.substr(open + 1, close - open - 1);
}

// AnonHugePages (in kB) of the mapping that holds `address`, from
// /proc/self/smaps.
long hugePagesKbAt(const void* address) {
  std::ifstream in("/proc/self/smaps");
  const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(address);
  bool inside = false;
  for (std::string line; std::getline(in, line);) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find(' ')) {
      inside = lo <= a && a < hi;
      continue;
    }
    if (inside && line.rfind("AnonHugePages:", 0) == 0)
      return std::stol(line.substr(std::string("AnonHugePages:").size()));
  }
  return -1;
}

}  // namespace

TEST(HugePages, HelpersAreReserveResizeAndAssign) {
  std::vector<int> v{1, 2, 3};
  reserveInHugePages(v, 100);
  EXPECT_EQ(v.size(), 3u);
  EXPECT_GE(v.capacity(), 100u);
  EXPECT_EQ(v, (std::vector<int>{1, 2, 3}));
  const std::size_t capacity = v.capacity();
  reserveInHugePages(v, 10);  // room enough already: nothing moves
  EXPECT_EQ(v.capacity(), capacity);

  resizeInHugePages(v, 6);
  EXPECT_EQ(v, (std::vector<int>{1, 2, 3, 0, 0, 0}));
  resizeInHugePages(v, 2);
  EXPECT_EQ(v, (std::vector<int>{1, 2}));

  assignInHugePages(v, 4, -1);
  EXPECT_EQ(v, (std::vector<int>{-1, -1, -1, -1}));
  const std::size_t large = std::size_t(3) << 20;  // 12 MiB of ints
  assignInHugePages(v, large, 7);
  ASSERT_EQ(v.size(), large);
  EXPECT_EQ(v.front(), 7);
  EXPECT_EQ(v[large / 2], 7);
  EXPECT_EQ(v.back(), 7);

  std::vector<double> big{2.5};
  resizeInHugePages(big, large);  // kept element, then value-initialized ones
  EXPECT_EQ(big[0], 2.5);
  EXPECT_EQ(big[1], 0.0);
  EXPECT_EQ(big.back(), 0.0);
}

TEST(HugePages, AdvisingSmallUnalignedOrEmptyRangesIsHarmless) {
  std::vector<char> small(1000, 'x');
  adviseHugePages(small.data(), small.size());
  adviseHugePages(small.data() + 1, 0);
  adviseHugePages(nullptr, 0);
  std::vector<char> large((std::size_t(9) << 20) + 3, 'y');
  adviseHugePages(large.data() + 3, large.size() - 3);  // written already: keeps its pages
  EXPECT_EQ(small[999], 'x');
  EXPECT_EQ(large[0], 'y');
  EXPECT_EQ(large.back(), 'y');
}

TEST(HugePages, LargeArraysAreInHugePagesWhereTheKernelGivesThem) {
  const std::string mode = hugePageMode();
  std::vector<std::uint64_t> v;
  resizeInHugePages(v, std::size_t(4) << 20);  // 32 MiB, written by the resize
  ASSERT_EQ(v.size(), std::size_t(4) << 20);
  EXPECT_EQ(v[12345], 0u);
  const long kb = hugePagesKbAt(v.data() + v.size() / 2);
  if (mode == "madvise" || mode == "always") {
    // Sixteen 2 MiB pages lie wholly inside; the kernel may fall back to
    // small pages for some when memory is fragmented, but not for all.
    EXPECT_GE(kb, 2048) << "transparent huge pages are '" << mode << "', yet the array has none";
  } else {
    EXPECT_LE(kb, 0) << "huge pages without the kernel offering them";
  }
}

// Default-initialized elements: records with a constructor get it, and
// constructor arguments reach it, as with std::allocator.
TEST(HugePages, DefaultInitAllocatorConstructsAsAsked) {
  struct Record {
    int set = 7;
    int given;
    Record() : given(-1) {}
    explicit Record(int g) : given(g) {}
  };
  std::vector<Record, DefaultInitAllocator<Record>> records;
  resizeInHugePages(records, std::size_t(1) << 20);
  ASSERT_EQ(records.size(), std::size_t(1) << 20);
  EXPECT_EQ(records[777].set, 7);
  EXPECT_EQ(records.back().given, -1);
  records.emplace_back(5);
  EXPECT_EQ(records.back().given, 5);
  std::vector<int, DefaultInitAllocator<int>> copy(3, 4);  // a value given is still copied
  EXPECT_EQ(copy[2], 4);
}
