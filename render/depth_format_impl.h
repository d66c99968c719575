// Inline, per-format depth encoding for the rasterizer's inner loop (one instantiation per format).
// depth_format.cpp's depthKey() dispatches to these, so there is exactly one definition of each
// format's arithmetic.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "render/depth_format.h"

namespace va {

inline uint32_t floatBits(float v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    return u;
}

// Clamps d into [lo, hi]; sets oor when it had to. d == lo returns lo itself, so d = -0.0 with
// lo = 0 encodes as +0.0 (a float key of -0.0 would sort after every positive depth). A NaN depth
// is out of range and clamped to the far end (never reaches an integer conversion). Written without
// branches (selects), so the rasterizer's batch loops over it vectorize (raster_kernel.h).
inline double clampDepth(double d, double lo, double hi, bool &oor) {
    oor = oor | (d < lo) | !(d <= hi);
    return d <= lo ? lo : (d <= hi ? d : hi);
}

// Returns the stored value (as double) and writes the ordering key.
template <DepthFormat F>
inline double encodeDepth(const DepthEncoder &e, double d, uint32_t &key, bool &oor) {
    constexpr double kInf = INFINITY;
    const double n = e.nearZ, f = e.farZ;
    switch (F) {
    case DepthFormat::linear_f32: {
        const float v = float(clampDepth(d, 0, kInf, oor));
        key = floatBits(v);
        return v;
    }
    case DepthFormat::inv_f32: {
        const float v = float(1.0 / clampDepth(d, 0, kInf, oor));
        key = ~floatBits(v);
        return v;
    }
    case DepthFormat::int31_inv: {
        const int32_t v = int32_t(2147483647.0 / clampDepth(d, 1.0, kInf, oor));
        key = uint32_t(2147483647 - v);
        return v;
    }
    case DepthFormat::uint32_inv: {
        const uint32_t v = uint32_t(4294967295.0 / clampDepth(d, 1.0, kInf, oor));
        key = ~v;
        return v;
    }
    case DepthFormat::uint32_inv1: {
        const uint32_t v = uint32_t(4294967295.0 / (clampDepth(d, 0, kInf, oor) + 1.0));
        key = ~v;
        return v;
    }
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::depth24plus: {  // WebGPU's depth24plus as its 24-bit implementation
        const double dc = clampDepth(d, n, f, oor);
        const double z = (f * (dc - n)) / (dc * (f - n));
        const double scale = F == DepthFormat::unorm16 ? 65535.0 : 16777215.0;
        double v = std::nearbyint(scale * z);  // round half to even (default rounding mode)
        v = v < 0 ? 0 : (v > scale ? scale : v);
        key = uint32_t(v);
        return v;
    }
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed: {
        // Reversed-Z on an integer buffer: z_rev = n(f-d)/(d(f-n)) = 1 - z, rounded like unorm*.
        const double dc = clampDepth(d, n, f, oor);
        const double z = (n * (f - dc)) / (dc * (f - n));
        const double scale = F == DepthFormat::unorm16_reversed ? 65535.0 : 16777215.0;
        double v = std::nearbyint(scale * z);
        v = v < 0 ? 0 : (v > scale ? scale : v);
        key = uint32_t(scale - v);  // nearer is larger
        return v;
    }
    case DepthFormat::unorm24_gl: {
        // OpenGL: z_ndc in [-1, 1] from the projection, divided in float; the viewport transform
        // 0.5 * z + 0.5 done in float; then the float converted to 24-bit unorm.
        const double dc = clampDepth(d, n, f, oor);
        const float zndc = float((f + n) / (f - n) - (2 * f * n) / ((f - n) * dc));
        const float w = zndc * 0.5f + 0.5f;
        double v = std::nearbyint(16777215.0 * double(w));
        v = v < 0 ? 0 : (v > 16777215.0 ? 16777215.0 : v);
        key = uint32_t(v);
        return v;
    }
    case DepthFormat::f32_gl: {
        // As unorm24_gl up to the window depth w, which a float buffer stores as it is.
        const double dc = clampDepth(d, n, f, oor);
        const float zndc = float((f + n) / (f - n) - (2 * f * n) / ((f - n) * dc));
        const float w = zndc * 0.5f + 0.5f;  // in [0, 1]: z_ndc >= -1 gives +0.0 at near
        key = floatBits(w);
        return w;
    }
    case DepthFormat::f32_gl_reversed: {
        // Reversed-Z without clip control: the projection's z row negated, so z_ndc runs from +1
        // at near to -1 at far, and the same viewport transform w = 0.5 z_ndc + 0.5 (GREATER test).
        const double dc = clampDepth(d, n, f, oor);
        const float zndc = float((2 * f * n) / ((f - n) * dc) - (f + n) / (f - n));
        const float w = zndc * 0.5f + 0.5f;
        key = ~floatBits(w);
        return w;
    }
    case DepthFormat::f32:
    case DepthFormat::depth32float: {  // WebGPU's depth32float: f32 with the standard [0, 1] projection
        const double dc = clampDepth(d, n, f, oor);
        const float v = float((f * (dc - n)) / (dc * (f - n)));
        key = floatBits(v);
        return v;
    }
    case DepthFormat::f32_reversed: {
        const double dc = clampDepth(d, n, f, oor);
        const float v = float((n * (f - dc)) / (dc * (f - n)));
        key = ~floatBits(v);
        return v;
    }
    case DepthFormat::f32_reversed_inf: {
        const float v = float(n / clampDepth(d, n, kInf, oor));
        key = ~floatBits(v);
        return v;
    }
    case DepthFormat::log24: {
        const double dc = clampDepth(d, n, f, oor);
        // e.logC is exactly 1 for plain log24, so 1 * dc is dc: the values log24 always stored.
        double v = std::nearbyint(16777215.0 * (std::log(e.logC * dc + 1) / e.logDenominator));
        v = v < 0 ? 0 : (v > 16777215.0 ? 16777215.0 : v);
        key = uint32_t(v);
        return v;
    }
    }
    key = 0;
    return 0;
}

// Calls fn.template operator()<F>() with the format as a compile-time constant.
template <typename Fn>
inline auto dispatchDepthFormat(DepthFormat f, Fn &&fn) {
    switch (f) {
    case DepthFormat::linear_f32: return fn.template operator()<DepthFormat::linear_f32>();
    case DepthFormat::inv_f32: return fn.template operator()<DepthFormat::inv_f32>();
    case DepthFormat::int31_inv: return fn.template operator()<DepthFormat::int31_inv>();
    case DepthFormat::uint32_inv: return fn.template operator()<DepthFormat::uint32_inv>();
    case DepthFormat::uint32_inv1: return fn.template operator()<DepthFormat::uint32_inv1>();
    case DepthFormat::unorm16: return fn.template operator()<DepthFormat::unorm16>();
    case DepthFormat::unorm24: return fn.template operator()<DepthFormat::unorm24>();
    case DepthFormat::unorm24_gl: return fn.template operator()<DepthFormat::unorm24_gl>();
    case DepthFormat::f32: return fn.template operator()<DepthFormat::f32>();
    case DepthFormat::f32_reversed: return fn.template operator()<DepthFormat::f32_reversed>();
    case DepthFormat::f32_reversed_inf: return fn.template operator()<DepthFormat::f32_reversed_inf>();
    case DepthFormat::log24: return fn.template operator()<DepthFormat::log24>();
    case DepthFormat::unorm16_reversed: return fn.template operator()<DepthFormat::unorm16_reversed>();
    case DepthFormat::unorm24_reversed: return fn.template operator()<DepthFormat::unorm24_reversed>();
    case DepthFormat::f32_gl: return fn.template operator()<DepthFormat::f32_gl>();
    case DepthFormat::f32_gl_reversed: return fn.template operator()<DepthFormat::f32_gl_reversed>();
    // Same arithmetic, so the same instantiation (no extra rasterizer kernels): encodeDepth
    // depends on F only through the arithmetic.
    case DepthFormat::depth32float: return fn.template operator()<DepthFormat::f32>();
    case DepthFormat::depth24plus: return fn.template operator()<DepthFormat::unorm24>();
    }
    return fn.template operator()<DepthFormat::f32>();
}

}  // namespace va
