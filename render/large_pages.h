// Per-pixel buffers on transparent huge pages (2 MiB) where the kernel allows it.
//
// A 1080p frame's buffers are 8 MB each and the rasterizer and the ray caster touch them all over:
// in 4 KiB pages that is 2,025 pages per buffer, far more than the TLB holds, and faulting each
// page in on first touch cost more than writing it (render/raycast.cpp measured 3.5 ms against
// 0.4 ms per 8 MB buffer). MADV_HUGEPAGE is only a hint (Embree asks the same for its BVH): where
// the kernel's THP setting is "never", nothing changes, and the contents are the same either way.
#pragma once

#include <cstdint>
#include <vector>

#include <sys/mman.h>

namespace va {

// Room for n elements in v (empty), its memory advised to be backed by huge pages before the
// first touch: pages are faulted in only as elements arrive, 2 MiB at a time.
template <class T, class A>
void reserveOnLargePages(std::vector<T, A> &v, size_t n) {
    v.clear();
    v.reserve(n);  // allocates without touching the pages
#ifdef MADV_HUGEPAGE
    constexpr uintptr_t kPage = 4096;
    const uintptr_t b = (reinterpret_cast<uintptr_t>(v.data()) + kPage - 1) & ~(kPage - 1);
    const uintptr_t e = (reinterpret_cast<uintptr_t>(v.data() + n)) & ~(kPage - 1);
    if (e > b) madvise(reinterpret_cast<void *>(b), e - b, MADV_HUGEPAGE);
#endif
}

// v = n copies of x, its memory advised to be backed by huge pages before the first touch.
template <class T, class A>
void assignOnLargePages(std::vector<T, A> &v, size_t n, T x) {
    reserveOnLargePages(v, n);
    v.assign(n, x);
}

}  // namespace va
