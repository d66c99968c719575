// The z-buffer tile kernel (raster_kernel.h) compiled for AVX2: CMakeLists.txt builds this file
// alone with -mavx2 (no -mfma: -ffp-contract=off stays, and FMA would change no result anyway since
// nothing is contracted). raster.cpp calls it only when __builtin_cpu_supports("avx2").
// Everything it instantiates lives in raster_detail::avx2 (VA_RASTER_ISA), so no AVX2 code can be
// linked in place of the baseline build's inline functions.
#if defined(__AVX2__)
#define VA_RASTER_ISA avx2
#include "render/raster_kernel.h"

namespace va::raster_detail {
ShadeFn shadeFunctionAvx2(DepthFormat format, bool perspective, bool exactDepth) {
    return selectShade(format, perspective, exactDepth);
}
WalkFn walkFunctionAvx2(DepthFormat format, bool exactDepth) { return selectWalk<true>(format, exactDepth); }
}  // namespace va::raster_detail
#else
#include "render/raster_kernel.h"

namespace va::raster_detail {
// Built without -mavx2 (not an x86-64 compiler): no AVX2 kernel, the baseline one runs.
ShadeFn shadeFunctionAvx2(DepthFormat, bool, bool) { return nullptr; }
WalkFn walkFunctionAvx2(DepthFormat, bool) { return nullptr; }
}  // namespace va::raster_detail
#endif
