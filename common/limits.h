// Resource limits (docs/limits.md): what one run may ask of the machine. Input that would exceed a
// limit is refused before the memory is allocated, with the number it needed, the limit and the flag
// that raises it; every limit is a flag on the commands that load scenes.
#pragma once

#include <cstdint>
#include <string>

#include "render/abuffer.h"

namespace va {

// Defaults a demanding user accepts; the reasons are in docs/limits.md.
constexpr int kDefaultMaxResolution = 16384;              // per side: the largest texture a GPU allocates
constexpr uint64_t kDefaultMaxTriangles = 100'000'000;    // about 6.4 GB of scene model, 15 GB with Embree
constexpr int kDefaultMaxRecursion = 16;                  // 2^17 - 2 secondary rays per pixel at worst
constexpr uint32_t kDefaultMaxABufferList = kABufferDefaultMaxList;
constexpr uint64_t kDefaultMaxJsonDepth = 512;            // nested arrays/objects in a JSON input (PHP's
                                                          //   json_decode default; glTF and scenes use < 20)

struct Limits {
    int maxResolution = kDefaultMaxResolution;  // width and height of a view, each: --max-resolution
    uint64_t maxTriangles = kDefaultMaxTriangles;  // triangles of a loaded scene: --max-triangles
    int maxRecursion = kDefaultMaxRecursion;    // the deepest --max-depth accepted when secondary rays
                                                //   are traced: --max-recursion
    uint32_t maxABufferList = kDefaultMaxABufferList;  // fragments in one pixel's A-buffer list:
                                                       //   --max-abuffer-list
    uint64_t maxMemory = 0;  // bytes the analysis may need at its peak (estimateMemory); 0 = no
                             //   check. The CLI's default is defaultMaxMemory(): --max-memory
};

// Three quarters of the memory this process may use: the smaller of the physical RAM and the
// cgroup's memory.max (a container's limit). The rest is the OS's, the page cache's and the
// estimate's margin of error.
uint64_t defaultMaxMemory();

// "8G", "512M", "1.5GiB", "2000000000": a byte count (binary units: K = 1024). False with a message
// naming the text and the accepted forms.
bool parseByteSize(const std::string &text, uint64_t *bytes, std::string *err);

// "1.50 GiB", "512 MiB", "100 B": for messages.
std::string formatBytes(uint64_t bytes);

// What one triangle costs a run, about: the scene model (indices, plane, ids, its share of the
// vertices: 64), Embree's copy and BVH (112) and one view's per-triangle buffers (80). For messages;
// estimateMemory (analysis/pipeline.h) adds the terms up for the actual settings.
constexpr uint64_t kBytesPerTriangle = 256;

// The triangle limit's check and message, shared by the loaders: `what` needs `need` triangles.
// Call it before allocating them.
bool checkTriangleLimit(uint64_t need, uint64_t limit, const std::string &what, std::string *err);

}  // namespace va
