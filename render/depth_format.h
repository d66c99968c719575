// Depth formats, emulated bit-exactly (docs/depth-formats.md, "Depth formats").
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
    // Added by issue 19 (docs/depth-formats.md): reversed-Z on integer buffers, float depth with
    // OpenGL's [-1, 1] range without clip control, and WebGPU's depth32float and depth24plus.
    unorm16_reversed,
    unorm24_reversed,
    f32_gl,
    f32_gl_reversed,
    depth32float,
    depth24plus,
};
constexpr int kDepthFormatCount = 18;
// The first twelve formats (docs/depth-formats.md's original table): the per-view z-fighting analysis's
// default set (defaultZFightFormats), so its report fields stay as they were; the others are opt-in.
constexpr int kClassicDepthFormatCount = 12;

struct DepthFormatInfo {
    DepthFormat format;
    const char *name;
    int bits;              // bits of the stored value
    bool nearerIsLarger;   // comparison direction of the stored value
    const char *stored;    // the stored value's formula, as docs/depth-formats.md writes it
};
const DepthFormatInfo &depthFormatInfo(DepthFormat f);
// All formats in docs/depth-formats.md's table order (the order ties are broken in).
const std::vector<DepthFormat> &allDepthFormats();
// The formats the per-view z-fighting analysis evaluates unless told otherwise: the classic twelve.
const std::vector<DepthFormat> &defaultZFightFormats();

// log24's constant C in log(C*d+1)/log(C*f+1): `log24` means C = 1; `log24:C=X` sets it.
constexpr double kLogDepthC = 1.0;

// A format as a view, a budget or a command line names it: the arithmetic (DepthFormat) and its
// parameter, log24's constant C (1 for every other format). Converts implicitly from a DepthFormat.
struct DepthFormatSpec {
    DepthFormat format = DepthFormat::f32;
    double logC = kLogDepthC;
    DepthFormatSpec() = default;
    DepthFormatSpec(DepthFormat f) : format(f) {}  // NOLINT: implicit by design
    DepthFormatSpec(DepthFormat f, double c) : format(f), logC(c) {}
    bool operator==(const DepthFormatSpec &) const = default;
};
// "log24:C=0.001" for log24 with C != 1 (the shortest decimal that reads back as C); otherwise the
// format's name ("log24" for C = 1).
std::string depthFormatName(const DepthFormatSpec &f);
// Parses a format name, or "log24:C=X" with X a finite number > 0 (C = 1 is plain log24); on
// failure, *err says which names exist. The DepthFormat overload refuses a parameter.
bool parseDepthFormat(std::string_view name, DepthFormatSpec *out, std::string *err);
bool parseDepthFormat(std::string_view name, DepthFormat *out, std::string *err);
// Checks that a format can encode depths over [near, far] (near/far already valid: 0 < near < far):
// log24's L = ln(C*far + 1) must be finite and > 0 (C*far + 1 rounds to 1 otherwise). On failure
// returns false and *err names the format, the value and a fix.
bool validateDepthFormatRange(const DepthFormatSpec &f, double nearZ, double farZ, std::string *err);

// A format bound to one view's near and far planes, with the constants its arithmetic needs.
struct DepthEncoder {
    DepthFormat format = DepthFormat::f32;
    double nearZ = 0.1, farZ = 1000;
    double logC = kLogDepthC;  // log24's C
    // Derived constants (set by makeDepthEncoder).
    double fOverFMinusN = 0;   // f / (f - n)
    double nOverFMinusN = 0;   // n / (f - n)  (times f - d over d for reversed)
    double logDenominator = 0; // log(C*f + 1)
    double minValidDepth = 0;  // below it the format cannot represent d
};
DepthEncoder makeDepthEncoder(const DepthFormatSpec &format, double nearZ, double farZ);
// The spec an encoder was made from.
inline DepthFormatSpec depthFormatSpec(const DepthEncoder &e) { return {e.format, e.logC}; }

// The stored value as the format holds it, widened to double (a float stays exactly that float,
// an integer stays that integer). *outOfRange is set when d lies outside what the format can
// represent (the value is then clamped to the nearest representable one, never wrapped).
double depthStoredValue(const DepthEncoder &e, double d, bool *outOfRange = nullptr);

// The ordering key of d's stored value: smaller = nearer; equal <=> equal stored values.
uint32_t depthKey(const DepthEncoder &e, double d, bool *outOfRange = nullptr);

// Converts a stored value back to its ordering key (used by audits that already hold stored values).
uint32_t depthKeyFromStored(const DepthEncoder &e, double stored);

// True for the formats whose stored value is an IEEE float (the key is its bit pattern).
bool depthFormatIsFloat(DepthFormat f);

}  // namespace va
