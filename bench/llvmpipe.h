// The z-buffer's peer in bench_table: Mesa's llvmpipe drawing the same triangles headless through
// EGL surfaceless (EGL_MESA_platform_surfaceless) into a depth24_stencil8 framebuffer, color writes
// off, depth test LESS, on one thread (LP_NUM_THREADS=0: llvmpipe rasterizes on the calling thread).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace va::bench {

struct LlvmpipeRun {
    bool ok = false;
    std::string error;            // why it did not run (no EGL, not llvmpipe, ...)
    std::string renderer;         // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
    std::vector<double> cpuSeconds;   // per repetition: process CPU time of clear + draw + glFinish
    std::vector<double> wallSeconds;  // per repetition: the same, wall clock
    std::vector<double> cullCpuSeconds;  // the same with back faces culled (GL_CULL_FACE)
    uint64_t samplesCovered = 0;  // GL_SAMPLES_PASSED with depth test ALWAYS: fragments rasterized
    uint64_t samplesPassed = 0;   // GL_SAMPLES_PASSED with depth test LESS: depth passes
};

// positions: xyz per vertex (world space); clipFromWorld: row-major 4x4 (clip = M * (p, 1)).
// Must run before any other EGL/GL use in the process (it sets llvmpipe's environment).
LlvmpipeRun drawWithLlvmpipe(const std::vector<float> &positions, const std::vector<uint32_t> &indices,
                             const float clipFromWorld[16], int width, int height, int reps);

}  // namespace va::bench
