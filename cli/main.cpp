#include <climits>

#include <malloc.h>

#include "cli/commands.h"

int main(int argc, char **argv) {
    // glibc hands a block of 128 KiB or more straight back to the kernel when it is freed (its
    // dynamic threshold rises to at most the largest block freed so far), and trims the heap's top.
    // A view allocates and frees per-pixel buffers of 2-16 MB per stage and per image, so their pages
    // were faulted in and zeroed again and again: about 10% of analyze's CPU on oa_thor at 1080p.
    // Blocks up to 32 MiB (glibc's ceiling) now come from the heap, which is never trimmed; larger
    // ones (a 4K view's buffers) are still mapped per use. Measured on oa_thor spawns shard 1/20 at
    // 1080p, 2 threads, 3 runs each: 4.66 -> 4.46 s wall, peak RSS 700 -> 712 MB.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
    return va::runCli(argc, argv);
}
