// The process's heap policy (glibc malloc), set once at the start of main by the programs that run
// views: visaudit and the benchmarks, so both measure the same allocator.
#pragma once

namespace va {

// Blocks up to 32 MiB from the heap, which is never trimmed; the heap's first GiB on transparent
// huge pages, one arena (process_heap.cpp says why and what was measured). Call before any thread
// starts.
void setUpProcessHeap();

}  // namespace va
