#include "common/base/huge_pages.h"

#include <cstdint>

#include <sys/mman.h>

namespace meshmend {

void adviseHugePages(const void* begin, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t kHugePage = std::uintptr_t(2) << 20;
  if (bytes < kLargeArrayBytes) return;
  const std::uintptr_t first = (std::uintptr_t(begin) + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t last = (std::uintptr_t(begin) + bytes) & ~(kHugePage - 1);
  // A hint: a kernel without huge pages refuses it (EINVAL), and the memory
  // is then what it would have been.
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)begin;
  (void)bytes;
#endif
}

}  // namespace meshmend
