#include "render/depth_format.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

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
    {DepthFormat::unorm16_reversed, "unorm16_reversed", 16, true, "round((2^16-1) * n(f-d)/(d(f-n)))"},
    {DepthFormat::unorm24_reversed, "unorm24_reversed", 24, true, "round((2^24-1) * n(f-d)/(d(f-n)))"},
    {DepthFormat::f32_gl, "f32_gl", 32, false, "float(0.5*z_ndc + 0.5), OpenGL z_ndc in [-1,1], in float"},
    {DepthFormat::f32_gl_reversed, "f32_gl_reversed", 32, true,
     "float(0.5*z_ndc + 0.5), z_ndc = 2fn/((f-n)d) - (f+n)/(f-n) in float (reversed, no clip control)"},
    {DepthFormat::depth32float, "depth32float", 32, false, "float(f(d-n)/(d(f-n))) (WebGPU depth32float)"},
    {DepthFormat::depth24plus, "depth24plus", 24, false,
     "round((2^24-1) * f(d-n)/(d(f-n))) (WebGPU depth24plus as 24-bit depth)"},
};

// The shortest decimal that reads back as x (std::to_chars: fixed or scientific, whichever is
// shorter): 0.001, 100, 1e-05.
std::string shortestDecimal(double x) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    return std::string(buf, r.ptr);
}

std::string knownNames() {
    std::string s = "known formats:";
    for (const auto &i : kInfo) s += std::string(" ") + i.name;
    return s + ", and log24:C=X (log24 with constant C = X > 0)";
}
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

const std::vector<DepthFormat> &defaultZFightFormats() {
    static const std::vector<DepthFormat> classic(allDepthFormats().begin(),
                                                  allDepthFormats().begin() + kClassicDepthFormatCount);
    return classic;
}

std::string depthFormatName(const DepthFormatSpec &f) {
    std::string name = depthFormatInfo(f.format).name;
    if (f.format == DepthFormat::log24 && f.logC != kLogDepthC) name += ":C=" + shortestDecimal(f.logC);
    return name;
}

bool parseDepthFormat(std::string_view name, DepthFormatSpec *out, std::string *err) {
    // "log24:C=X": the log format's constant as a parameter.
    constexpr std::string_view kLogPrefix = "log24:C=";
    if (name.substr(0, kLogPrefix.size()) == kLogPrefix) {
        const std::string num(name.substr(kLogPrefix.size()));
        char *end = nullptr;
        const double c = num.empty() ? NAN : std::strtod(num.c_str(), &end);
        if (num.empty() || end != num.c_str() + num.size() || !std::isfinite(c) || !(c > 0)) {
            if (err)
                *err = "depth format '" + std::string(name) + "': C must be a finite number > 0, e.g. log24:C=0.001";
            return false;
        }
        *out = {DepthFormat::log24, c};
        return true;
    }
    for (const auto &i : kInfo)
        if (name == i.name) {
            *out = DepthFormatSpec(i.format);
            return true;
        }
    if (err) *err = "unknown depth format '" + std::string(name) + "'; " + knownNames();
    return false;
}

bool parseDepthFormat(std::string_view name, DepthFormat *out, std::string *err) {
    DepthFormatSpec spec;
    if (!parseDepthFormat(name, &spec, err)) return false;
    if (spec != DepthFormatSpec(spec.format)) {
        if (err) *err = "depth format '" + std::string(name) + "' takes no parameter here; use plain " +
                        depthFormatInfo(spec.format).name;
        return false;
    }
    *out = spec.format;
    return true;
}

bool validateDepthFormatRange(const DepthFormatSpec &f, double nearZ, double farZ, std::string *err) {
    (void)nearZ;
    if (f.format != DepthFormat::log24) return true;
    const double L = std::log(f.logC * farZ + 1);
    if (std::isfinite(L) && L > 0) return true;
    if (err)
        *err = "depth format " + depthFormatName(f) + " cannot encode depths up to far " + shortestDecimal(farZ) +
               ": log(C*far + 1) is " + (std::isfinite(L) ? "0 (C*far is below the double's resolution of 1)"
                                                              : "not finite (C*far overflows)") +
               "; choose C nearer 1/far, e.g. log24:C=" + shortestDecimal(1 / farZ);
    return false;
}

DepthEncoder makeDepthEncoder(const DepthFormatSpec &format, double nearZ, double farZ) {
    DepthEncoder e;
    e.format = format.format;
    e.logC = format.format == DepthFormat::log24 ? format.logC : kLogDepthC;
    e.nearZ = nearZ;
    e.farZ = farZ;
    e.fOverFMinusN = farZ / (farZ - nearZ);
    e.nOverFMinusN = nearZ / (farZ - nearZ);
    e.logDenominator = std::log(e.logC * farZ + 1);
    switch (e.format) {
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

bool depthFormatIsFloat(DepthFormat f) {
    switch (f) {
    case DepthFormat::linear_f32:
    case DepthFormat::inv_f32:
    case DepthFormat::f32:
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_reversed_inf:
    case DepthFormat::f32_gl:
    case DepthFormat::f32_gl_reversed:
    case DepthFormat::depth32float: return true;
    default: return false;
    }
}

uint32_t depthKeyFromStored(const DepthEncoder &e, double stored) {
    const DepthFormatInfo &info = depthFormatInfo(e.format);
    uint32_t raw = depthFormatIsFloat(e.format) ? floatBits(float(stored)) : uint32_t(stored);
    if (!info.nearerIsLarger) return raw;
    if (e.format == DepthFormat::int31_inv) return uint32_t(2147483647 - int32_t(raw));
    if (e.format == DepthFormat::unorm16_reversed) return 65535u - raw;
    if (e.format == DepthFormat::unorm24_reversed) return 16777215u - raw;
    return ~raw;
}

}  // namespace va
