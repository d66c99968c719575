// The process's heap policy (common/process_heap.h): the heap's first GiB advised for huge pages,
// and every thread's large blocks taken from it. Each test runs in a process of its own
// (gtest_discover_tests), so setting the policy here touches no other test.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>

#include <gtest/gtest.h>

#include "common/process_heap.h"

namespace {

struct Mapping {
    uintptr_t begin = 0, end = 0;
    bool heap = false;      // the [heap] (brk) mapping
    bool hugeHint = false;  // VmFlags "hg": advised MADV_HUGEPAGE
};

std::vector<Mapping> mappings() {
    std::vector<Mapping> out;
    std::ifstream f("/proc/self/smaps");
    std::string line;
    while (std::getline(f, line)) {
        unsigned long a = 0, b = 0;
        if (std::sscanf(line.c_str(), "%lx-%lx ", &a, &b) == 2) {  // a mapping's first line
            out.push_back({uintptr_t(a), uintptr_t(b), line.find("[heap]") != std::string::npos, false});
        } else if (line.rfind("VmFlags:", 0) == 0 && !out.empty()) {
            std::istringstream flags(line.substr(8));
            for (std::string fl; flags >> fl;) out.back().hugeHint |= fl == "hg";
        }
    }
    return out;
}

// Bytes of [p, p + n) in [heap] mappings, and of those in mappings advised for huge pages.
struct Overlap {
    size_t heap = 0, advised = 0;
};
Overlap heapOverlap(const std::vector<Mapping> &maps, const void *p, size_t n) {
    const uintptr_t a = reinterpret_cast<uintptr_t>(p), e = a + n;
    Overlap o;
    for (const Mapping &m : maps) {
        if (!m.heap || m.end <= a || m.begin >= e) continue;
        const size_t bytes = std::min(e, m.end) - std::max(a, m.begin);
        o.heap += bytes;
        if (m.hugeHint) o.advised += bytes;
    }
    return o;
}

bool policyApplies(std::string *why) {
#if defined(__SANITIZE_ADDRESS__)
    *why = "AddressSanitizer's allocator has no brk heap";
    return false;
#endif
    for (int limit : {RLIMIT_AS, RLIMIT_DATA})
        if (rlimit r{}; getrlimit(limit, &r) == 0 && r.rlim_cur != RLIM_INFINITY) {
            *why = "the process runs under a limit on its address space or data (the policy steps aside)";
            return false;
        }
    std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string modes;
    std::getline(thp, modes);
    if (modes.empty() || modes.find("[never]") != std::string::npos) {
        *why = "transparent huge pages are off on this kernel";
        return false;
    }
    return true;
}

TEST(ProcessHeap, FirstGibAdvisedForHugePagesAndEveryThreadsBlocksFromIt) {
    std::string why;
    if (!policyApplies(&why)) GTEST_SKIP() << why;
    va::setUpProcessHeap();
    const std::vector<Mapping> maps = mappings();
    uintptr_t advised = 0;
    for (const Mapping &m : maps)
        if (m.heap && m.hugeHint) advised += m.end - m.begin;
    // The reserve, less what rounding its ends to 2 MiB cut off.
    EXPECT_GE(advised, (uintptr_t(1) << 30) - (uintptr_t(4) << 20));

    // An 8 MB block (a 1080p id buffer) from this thread and from another one: both on the heap
    // (below the 32 MiB mapping threshold, and one arena), not in mappings of their own, and
    // advised but for at most the heap's part below the reserve (the top chunk the reserve grew
    // from, and the rounding to 2 MiB).
    constexpr size_t kBlock = size_t(8) << 20, kSlack = size_t(4) << 20;
    void *mine = std::malloc(kBlock);
    void *theirs = nullptr;
    std::thread([&] { theirs = std::malloc(kBlock); }).join();
    const std::vector<Mapping> after = mappings();
    const Overlap a = heapOverlap(after, mine, kBlock), b = heapOverlap(after, theirs, kBlock);
    EXPECT_EQ(a.heap, kBlock) << "this thread's 8 MB block is not on the heap";
    EXPECT_EQ(b.heap, kBlock) << "another thread's 8 MB block is not on the heap (an arena of its own?)";
    EXPECT_GE(a.advised + kSlack, kBlock);
    EXPECT_GE(b.advised + kSlack, kBlock);
    std::free(mine);
    std::free(theirs);
}

}  // namespace
