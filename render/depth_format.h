// Depth formats, emulated bit-exactly (DESIGN.md, "Depth formats").
//
// A format maps a fragment's view depth d (double, > 0) to the value a depth buffer of that format
// stores, with that format's own arithmetic. For the z-buffer every stored value is also mapped to
// an unsigned 32-bit *ordering key*: smaller key = nearer, equal keys <=> equal stored values. The
// depth test is then one unsigned LESS for every format, and ties behave exactly as stored values do.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace va {

enum class DepthFormat : uint8_t {
    linear_f32,
    inv_f32,
    int31_inv,
    uint32_inv,
    uint32_inv1,
    unorm16,
    unorm24,
    unorm24_gl,
    f32,
    f32_reversed,
    f32_reversed_inf,
    log24,
};
constexpr int kDepthFormatCount = 12;

struct DepthFormatInfo {
    DepthFormat format;
    const char *name;
    int bits;              // bits of the stored value
    bool nearerIsLarger;   // comparison direction of the stored value
    const char *stored;    // the stored value's formula, as DESIGN.md writes it
};
const DepthFormatInfo &depthFormatInfo(DepthFormat f);
// All formats in DESIGN.md's table order (the order ties are broken in).
const std::vector<DepthFormat> &allDepthFormats();
// Parses a format name; on failure, *err says which names exist.
bool parseDepthFormat(std::string_view name, DepthFormat *out, std::string *err);

// log24's constant C in log(C*d+1)/log(C*f+1).
constexpr double kLogDepthC = 1.0;

// A format bound to one view's near and far planes, with the constants its arithmetic needs.
struct DepthEncoder {
    DepthFormat format = DepthFormat::f32;
    double nearZ = 0.1, farZ = 1000;
    // Derived constants (set by makeDepthEncoder).
    double fOverFMinusN = 0;   // f / (f - n)
    double nOverFMinusN = 0;   // n / (f - n)  (times f - d over d for reversed)
    double logDenominator = 0; // log(C*f + 1)
    double minValidDepth = 0;  // below it the format cannot represent d
};
DepthEncoder makeDepthEncoder(DepthFormat format, double nearZ, double farZ);

// The stored value as the format holds it, widened to double (a float stays exactly that float,
// an integer stays that integer). *outOfRange is set when d lies outside what the format can
// represent (the value is then clamped to the nearest representable one, never wrapped).
double depthStoredValue(const DepthEncoder &e, double d, bool *outOfRange = nullptr);

// The ordering key of d's stored value: smaller = nearer; equal <=> equal stored values.
uint32_t depthKey(const DepthEncoder &e, double d, bool *outOfRange = nullptr);

// Converts a stored value back to its ordering key (used by audits that already hold stored values).
uint32_t depthKeyFromStored(const DepthEncoder &e, double stored);

}  // namespace va
