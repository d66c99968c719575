// Depth formats: hand-computed stored values, ordering keys, range handling (docs/depth-formats.md, Depth formats).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "render/depth_format.h"
#include "render/depth_format_impl.h"

namespace va {
namespace {

double stored(DepthFormat f, double n, double fa, double d, bool *oor = nullptr) {
    return depthStoredValue(makeDepthEncoder(f, n, fa), d, oor);
}

TEST(DepthFormat, HandComputedIntegerValues) {
    // uint32_inv1: floor((2^32 - 1) / (d + 1)); 4294967295 / 11 = 390451572.27..., / 1001 = 4290676.6...
    EXPECT_EQ(stored(DepthFormat::uint32_inv1, 0.1, 1000, 10), 390451572.0);
    EXPECT_EQ(stored(DepthFormat::uint32_inv1, 0.1, 1000, 1000), 4290676.0);
    // int31_inv: floor((2^31 - 1) / d); 2147483647 / 10 = 214748364.7
    EXPECT_EQ(stored(DepthFormat::int31_inv, 0.1, 1000, 10), 214748364.0);
    // uint32_inv: floor((2^32 - 1) / d); 4294967295 / 4 = 1073741823.75
    EXPECT_EQ(stored(DepthFormat::uint32_inv, 0.1, 1000, 4), 1073741823.0);
    // unorm16 at d = 2n: f(d - n)/(d(f - n)) = f/(2(f - n)); n = 1, f = 3: 0.75 -> round(49151.25)
    EXPECT_EQ(stored(DepthFormat::unorm16, 1, 3, 2), 49151.0);
}

TEST(DepthFormat, Unorm24Endpoints) {
    for (double n : {0.01, 0.1, 0.5, 1.0}) {
        for (double f : {10.0, 200.0, 1e5}) {
            bool oor = true;
            EXPECT_EQ(stored(DepthFormat::unorm24, n, f, n, &oor), 0.0) << n << " " << f;
            EXPECT_FALSE(oor);
            // At d = f the ratio is f(f - n) / (f(f - n)): the same double twice, exactly 1.
            EXPECT_EQ(stored(DepthFormat::unorm24, n, f, f, &oor), 16777215.0) << n << " " << f;
            EXPECT_FALSE(oor);
            EXPECT_EQ(stored(DepthFormat::unorm16, n, f, f), 65535.0);
            EXPECT_EQ(stored(DepthFormat::log24, n, f, f), 16777215.0);
        }
    }
}

TEST(DepthFormat, ReversedIsExactlyOneAtNear) {
    for (double n : {0.001, 0.1, 0.5, 3.0}) {
        EXPECT_EQ(stored(DepthFormat::f32_reversed, n, 1000, n), 1.0) << n;
        EXPECT_EQ(stored(DepthFormat::f32_reversed, n, 1000, 1000), 0.0) << n;
        EXPECT_EQ(stored(DepthFormat::f32_reversed_inf, n, 1000, n), 1.0) << n;
        EXPECT_EQ(stored(DepthFormat::f32, n, 1000, n), 0.0) << n;
        EXPECT_EQ(stored(DepthFormat::f32, n, 1000, 1000), 1.0) << n;
    }
    // float rounding, not double: f32_reversed_inf at d = 3n is float(1/3).
    EXPECT_EQ(stored(DepthFormat::f32_reversed_inf, 0.5, 100, 1.5), double(float(1.0 / 3.0)));
    EXPECT_EQ(stored(DepthFormat::linear_f32, 0.5, 100, 0.1), double(0.1f));
}

TEST(DepthFormat, OutOfRangeClampsNeverWraps) {
    bool oor = false;
    // (2^32 - 1) / 0.5 would not fit in 32 bits: clamped to d = 1, i.e. the largest value.
    EXPECT_EQ(stored(DepthFormat::uint32_inv, 0.1, 1000, 0.5, &oor), 4294967295.0);
    EXPECT_TRUE(oor);
    oor = false;
    EXPECT_EQ(stored(DepthFormat::int31_inv, 0.1, 1000, 0.25, &oor), 2147483647.0);
    EXPECT_TRUE(oor);
    oor = false;
    EXPECT_EQ(stored(DepthFormat::unorm24, 0.5, 200, 0.25, &oor), 0.0);
    EXPECT_TRUE(oor);
    oor = false;
    EXPECT_EQ(stored(DepthFormat::unorm24, 0.5, 200, 500, &oor), 16777215.0);
    EXPECT_TRUE(oor);
    oor = false;
    EXPECT_EQ(stored(DepthFormat::f32_reversed, 0.5, 200, 500, &oor), 0.0);
    EXPECT_TRUE(oor);
    oor = true;
    stored(DepthFormat::uint32_inv, 0.1, 1000, 1.0, &oor);  // exactly at the limit: in range
    EXPECT_FALSE(oor);
    // The key of a clamped value is the key of the limit.
    const DepthEncoder e = makeDepthEncoder(DepthFormat::uint32_inv, 0.1, 1000);
    EXPECT_EQ(depthKey(e, 0.5), depthKey(e, 1.0));
}

// Negative zero and NaN must not produce keys out of order (found while writing these tests:
// clampDepth passed -0.0 through, so linear_f32 keyed d = -0 as the farthest depth of all and
// inv_f32 stored -inf; a NaN depth reached an integer conversion).
TEST(DepthFormat, NegativeZeroAndNaN) {
    for (DepthFormat f : allDepthFormats()) {
        const DepthEncoder e = makeDepthEncoder(f, 0.5, 200);
        bool oorPos = false, oorNeg = false;
        const uint32_t kp = depthKey(e, 0.0, &oorPos), kn = depthKey(e, -0.0, &oorNeg);
        EXPECT_EQ(kp, kn) << depthFormatInfo(f).name;
        EXPECT_EQ(oorPos, oorNeg) << depthFormatInfo(f).name;
        EXPECT_EQ(depthStoredValue(e, 0.0), depthStoredValue(e, -0.0)) << depthFormatInfo(f).name;
        EXPECT_LE(kp, depthKey(e, 1.0)) << depthFormatInfo(f).name;
        bool oor = false;
        const uint32_t knan = depthKey(e, std::nan(""), &oor);
        EXPECT_TRUE(oor) << depthFormatInfo(f).name;
        EXPECT_EQ(knan, depthKey(e, std::numeric_limits<double>::infinity())) << depthFormatInfo(f).name;
    }
}

// Over a dense geometric sweep of depths (inside and outside [near, far]) every format's key is
// non-decreasing in d, equal keys occur exactly for equal stored values, and the key recomputed
// from the stored value is the same key.
TEST(DepthFormat, KeyOrderMatchesComparisonDirection) {
    const double ranges[][2] = {{0.5, 200}, {0.1, 1000}, {1e-3, 1e6}, {2, 3}};
    for (const auto &r : ranges) {
        const double n = r[0], f = r[1];
        std::vector<double> ds;
        for (double d = n * 0.25; d < f * 4; d *= 1.0007) ds.push_back(d);
        ds.push_back(n);
        ds.push_back(f);
        std::sort(ds.begin(), ds.end());
        for (DepthFormat fmt : allDepthFormats()) {
            const DepthEncoder e = makeDepthEncoder(fmt, n, f);
            const DepthFormatInfo &info = depthFormatInfo(fmt);
            uint32_t prevKey = 0;
            double prevStored = 0;
            int distinct = 0;
            for (size_t i = 0; i < ds.size(); ++i) {
                const uint32_t k = depthKey(e, ds[i]);
                const double s = depthStoredValue(e, ds[i]);
                ASSERT_EQ(depthKeyFromStored(e, s), k) << info.name << " d=" << ds[i];
                if (i > 0) {
                    ASSERT_LE(prevKey, k) << info.name << " d=" << ds[i];
                    ASSERT_EQ(prevKey == k, prevStored == s) << info.name << " d=" << ds[i];
                    // The stored value moves the way the format's comparison direction says.
                    if (info.nearerIsLarger) ASSERT_GE(prevStored, s) << info.name << " d=" << ds[i];
                    else ASSERT_LE(prevStored, s) << info.name << " d=" << ds[i];
                    distinct += prevKey != k;
                }
                prevKey = k;
                prevStored = s;
            }
            // Not a constant function: every format resolves depths in a range this wide.
            EXPECT_GT(distinct, 10) << info.name << " n=" << n << " f=" << f;
        }
    }
}

TEST(DepthFormat, ExtremeRangeNoNaNNoOverflow) {
    const double n = 1e-3, f = 1e6;
    for (DepthFormat fmt : allDepthFormats()) {
        const DepthEncoder e = makeDepthEncoder(fmt, n, f);
        const DepthFormatInfo &info = depthFormatInfo(fmt);
        for (double d : {n, 2 * n, 1.0, 1e3, 0.5 * f, f}) {
            bool oor = true;
            const double s = depthStoredValue(e, d, &oor);
            EXPECT_TRUE(std::isfinite(s)) << info.name << " d=" << d;
            EXPECT_GE(s, 0) << info.name << " d=" << d;
            if (info.bits < 32 || fmt == DepthFormat::int31_inv || fmt == DepthFormat::uint32_inv ||
                fmt == DepthFormat::uint32_inv1) {
                EXPECT_LE(s, std::ldexp(1.0, info.bits) - 1) << info.name << " d=" << d;
            }
            // Formats with a lower limit of 1 (int31_inv, uint32_inv) cannot hold d < 1.
            EXPECT_EQ(oor, d < e.minValidDepth) << info.name << " d=" << d;
        }
    }
}

TEST(DepthFormat, ParseListsKnownFormats) {
    DepthFormat f = DepthFormat::f32;
    std::string err;
    EXPECT_TRUE(parseDepthFormat("unorm24_gl", &f, &err));
    EXPECT_EQ(f, DepthFormat::unorm24_gl);
    EXPECT_FALSE(parseDepthFormat("d24s8", &f, &err));
    EXPECT_EQ(err,
              "unknown depth format 'd24s8'; known formats: linear_f32 inv_f32 int31_inv uint32_inv "
              "uint32_inv1 unorm16 unorm24 unorm24_gl f32 f32_reversed f32_reversed_inf log24 unorm16_reversed "
              "unorm24_reversed f32_gl f32_gl_reversed depth32float depth24plus, and log24:C=X (log24 with "
              "constant C = X > 0)");
    EXPECT_EQ(f, DepthFormat::unorm24_gl);  // untouched on failure
    // Every name in the table parses back to its format.
    for (DepthFormat g : allDepthFormats()) {
        DepthFormat h = DepthFormat::linear_f32;
        EXPECT_TRUE(parseDepthFormat(depthFormatInfo(g).name, &h, nullptr));
        EXPECT_EQ(h, g);
    }
    EXPECT_EQ(int(allDepthFormats().size()), kDepthFormatCount);
}

}  // namespace
}  // namespace va
