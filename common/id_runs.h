// Runs of equal values in a per-pixel id buffer.
//
// Most pixels of a view show their left neighbour's triangle, so a count per triangle or per object
// taken a run at a time makes one table update per run instead of one per pixel (and an update per
// pixel waits on the one before it whenever both hit the same counter).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace va {

// Calls fn(id, count) for each run of equal ids, in order.
template <class Fn>
void forEachIdRun(std::span<const uint32_t> ids, Fn &&fn) {
    const size_t n = ids.size();
    for (size_t i = 0; i < n;) {
        const uint32_t id = ids[i];
        size_t j = i + 1;
        while (j < n && ids[j] == id) ++j;
        fn(id, uint64_t(j - i));
        i = j;
    }
}

}  // namespace va
