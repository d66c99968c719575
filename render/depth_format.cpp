#include "render/depth_format.h"

#include <cmath>

#include "render/depth_format_impl.h"

namespace va {

namespace {
const DepthFormatInfo kInfo[kDepthFormatCount] = {
    {DepthFormat::linear_f32, "linear_f32", 32, false, "float(d)"},
    {DepthFormat::inv_f32, "inv_f32", 32, true, "float(1/d)"},
    {DepthFormat::int31_inv, "int31_inv", 31, true, "(int32)((2^31-1)/d)"},
    {DepthFormat::uint32_inv, "uint32_inv", 32, true, "(uint32)((2^32-1)/d)"},
    {DepthFormat::uint32_inv1, "uint32_inv1", 32, true, "(uint32)((2^32-1)/(d+1))"},
    {DepthFormat::unorm16, "unorm16", 16, false, "round((2^16-1) * f(d-n)/(d(f-n)))"},
    {DepthFormat::unorm24, "unorm24", 24, false, "round((2^24-1) * f(d-n)/(d(f-n)))"},
    {DepthFormat::unorm24_gl, "unorm24_gl", 24, false,
     "round((2^24-1) * (0.5*z_ndc + 0.5)), OpenGL z_ndc in [-1,1], in float"},
    {DepthFormat::f32, "f32", 32, false, "float(f(d-n)/(d(f-n)))"},
    {DepthFormat::f32_reversed, "f32_reversed", 32, true, "float(n(f-d)/(d(f-n)))"},
    {DepthFormat::f32_reversed_inf, "f32_reversed_inf", 32, true, "float(n/d)"},
    {DepthFormat::log24, "log24", 24, false, "round((2^24-1) * log(C*d+1)/log(C*f+1)), C = 1"},
};
}  // namespace

const DepthFormatInfo &depthFormatInfo(DepthFormat f) { return kInfo[int(f)]; }

const std::vector<DepthFormat> &allDepthFormats() {
    static const std::vector<DepthFormat> all = [] {
        std::vector<DepthFormat> v;
        for (const auto &i : kInfo) v.push_back(i.format);
        return v;
    }();
    return all;
}

bool parseDepthFormat(std::string_view name, DepthFormat *out, std::string *err) {
    for (const auto &i : kInfo)
        if (name == i.name) {
            *out = i.format;
            return true;
        }
    if (err) {
        *err = "unknown depth format '" + std::string(name) + "'; known formats:";
        for (const auto &i : kInfo) *err += std::string(" ") + i.name;
    }
    return false;
}

DepthEncoder makeDepthEncoder(DepthFormat format, double nearZ, double farZ) {
    DepthEncoder e;
    e.format = format;
    e.nearZ = nearZ;
    e.farZ = farZ;
    e.fOverFMinusN = farZ / (farZ - nearZ);
    e.nOverFMinusN = nearZ / (farZ - nearZ);
    e.logDenominator = std::log(kLogDepthC * farZ + 1);
    switch (format) {
    case DepthFormat::int31_inv:
    case DepthFormat::uint32_inv: e.minValidDepth = 1; break;
    case DepthFormat::linear_f32:
    case DepthFormat::inv_f32:
    case DepthFormat::uint32_inv1: e.minValidDepth = 0; break;
    default: e.minValidDepth = nearZ; break;
    }
    return e;
}

double depthStoredValue(const DepthEncoder &e, double d, bool *outOfRange) {
    uint32_t key;
    bool oor = false;
    const double v = dispatchDepthFormat(e.format, [&]<DepthFormat F>() { return encodeDepth<F>(e, d, key, oor); });
    if (outOfRange) *outOfRange = oor;
    return v;
}

uint32_t depthKey(const DepthEncoder &e, double d, bool *outOfRange) {
    uint32_t key = 0;
    bool oor = false;
    dispatchDepthFormat(e.format, [&]<DepthFormat F>() { return encodeDepth<F>(e, d, key, oor); });
    if (outOfRange) *outOfRange = oor;
    return key;
}

uint32_t depthKeyFromStored(const DepthEncoder &e, double stored) {
    const DepthFormatInfo &info = depthFormatInfo(e.format);
    const bool isFloat = e.format == DepthFormat::linear_f32 || e.format == DepthFormat::inv_f32 ||
                         e.format == DepthFormat::f32 || e.format == DepthFormat::f32_reversed ||
                         e.format == DepthFormat::f32_reversed_inf;
    uint32_t raw = isFloat ? floatBits(float(stored)) : uint32_t(stored);
    if (!info.nearerIsLarger) return raw;
    if (e.format == DepthFormat::int31_inv) return uint32_t(2147483647 - int32_t(raw));
    return ~raw;
}

}  // namespace va
