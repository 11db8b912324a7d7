// Large arrays in transparent huge pages.
//
// The first write to each 4 KiB page of new memory is a page fault, and on
// a virtual machine one costs microseconds (about 11 µs on the 2-core VMs
// the benchmarks run on, 210 ms for 64 MiB): a split of the full bunny and
// dragon wrote some 60,000 new pages, a third of its time. Where the kernel
// gives transparent huge pages on request (/sys/kernel/mm/
// transparent_hugepage/enabled set to "madvise", as on those machines, or
// "always"), a 2 MiB page is one fault (the same 64 MiB: 4 ms).
//
// These helpers ask for huge pages for the whole 2 MiB pages inside a large
// array's memory before anything writes to it. It is a hint: where huge
// pages are not given, or for arrays under 4 MiB, they are reserve and
// resize. The memory stays the array's, freed as it always is.
#pragma once

#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

namespace meshmend {

// The size from which an array is worth advising (two huge pages, so that
// at least one lies wholly inside it).
inline constexpr std::size_t kLargeArrayBytes = std::size_t(4) << 20;

// Asks for huge pages for the 2 MiB pages that lie wholly inside [begin,
// begin + bytes) (none under 4 MiB). Pages written already keep theirs.
void adviseHugePages(const void* begin, std::size_t bytes);

// An allocator that default-initializes new elements where std::allocator
// value-initializes them (zeroes them first): for large arrays of records
// each of which is written whole before it is read, a pass over the memory
// less.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// v.reserve(n), the room beyond v's elements advised before it is written.
template <class T, class A>
void reserveInHugePages(std::vector<T, A>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  adviseHugePages(v.data() + v.size(), (v.capacity() - v.size()) * sizeof(T));
}

// v.resize(n) (value-initialized new elements), the new memory advised first.
template <class T, class A>
void resizeInHugePages(std::vector<T, A>& v, std::size_t n) {
  reserveInHugePages(v, n);
  v.resize(n);
}

// v.assign(n, value), the new memory advised first.
template <class T>
void assignInHugePages(std::vector<T>& v, std::size_t n, const T& value) {
  if (n > v.capacity()) {
    v = std::vector<T>();  // nothing to keep: no copy into the new memory
    reserveInHugePages(v, n);
  }
  v.assign(n, value);
}

}  // namespace meshmend
