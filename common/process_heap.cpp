#include "common/process_heap.h"

#include <climits>
#include <cstdint>
#include <cstdlib>
#include <initializer_list>

#include <malloc.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

namespace va {

namespace {

// The heap on transparent huge pages (2 MiB). Blocks up to 32 MiB come from the heap (below), in
// 4 KiB pages: a 1080p view touches ~500 MB of them, so a level run faulted in ~130k pages, and on
// this kind of virtual machine a 4 KiB fault costs ~12 us (the page tables are the hypervisor's
// too), besides the TLB misses of buffers read all over. glibc marks the heap for huge pages only
// with GLIBC_TUNABLES=glibc.malloc.hugetlb=1 from the environment, so here: the heap grows once by
// kHeapReserve now (address space only: pages are faulted in as they are touched, as before) and
// that range is advised MADV_HUGEPAGE. One arena, so the other threads' blocks come from it too (a
// thread's own arena is mapped apart, in 4 KiB pages; per-thread caches still serve small blocks
// without the lock, but work made of little else but small allocations takes turns on it: the
// report's JSON is built on one thread for that, reports/report_json.cpp). Only a hint: where THP
// is "never", the heap cannot grow, or the process runs under a limit on its address space or data
// size, nothing changes, and past kHeapReserve the heap grows in 4 KiB pages again. Measured on
// oa_thor spawns, 34-view shard at 1080p, 2 threads, alternating three times: 5.80-6.12 ->
// 5.13-5.19 s wall, user CPU 9.97-10.53 -> 8.46-8.67 s, minor faults 112-117k -> 1.9-2.1k, peak RSS
// unchanged.
void heapOnHugePages() {
    constexpr size_t kHeapReserve = size_t(1) << 30;
    constexpr uintptr_t kHuge = uintptr_t(2) << 20;
    // Under a limit on address space or data (ulimit -v, -d) the reserve would spend a GiB of it.
    for (int limit : {RLIMIT_AS, RLIMIT_DATA})
        if (rlimit r{}; getrlimit(limit, &r) == 0 && r.rlim_cur != RLIM_INFINITY) return;
    mallopt(M_ARENA_MAX, 1);
    mallopt(M_TOP_PAD, int(kHeapReserve));
    const uintptr_t before = reinterpret_cast<uintptr_t>(sbrk(0));
    void *volatile grow = std::malloc(16 << 20);  // volatile: the pair is not optimized away
    std::free(grow);
    mallopt(M_TOP_PAD, 128 << 10);                // glibc's default again
    const uintptr_t after = reinterpret_cast<uintptr_t>(sbrk(0));
    const uintptr_t b = (before + kHuge - 1) & ~(kHuge - 1), e = after & ~(kHuge - 1);
    if (before != uintptr_t(-1) && e > b) madvise(reinterpret_cast<void *>(b), e - b, MADV_HUGEPAGE);
}

}  // namespace

void setUpProcessHeap() {
    // glibc hands a block of 128 KiB or more straight back to the kernel when it is freed (its
    // dynamic threshold rises to at most the largest block freed so far), and trims the heap's top.
    // A view allocates and frees per-pixel buffers of 2-16 MB per stage and per image, so their pages
    // were faulted in and zeroed again and again: about 10% of analyze's CPU on oa_thor at 1080p.
    // Blocks up to 32 MiB (glibc's ceiling) now come from the heap, which is never trimmed; larger
    // ones (a 4K view's buffers) are still mapped per use. Measured on oa_thor spawns shard 1/20 at
    // 1080p, 2 threads, 3 runs each: 4.66 -> 4.46 s wall, peak RSS 700 -> 712 MB.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
    heapOnHugePages();
}

}  // namespace va
