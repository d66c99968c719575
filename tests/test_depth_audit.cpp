// The depth-format audit (analysis/audits/depth_audit.h), its table and JSON, and its plot: hand-computed
// resolutions, exact distinct-value counts, inverse round trips over wide magnitudes, fight
// predicates and onsets against analytic bounds, bad input, and the PNG read back (readImage).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <fstream>
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "analysis/audits/depth_audit.h"
#include "analysis/audits/zfight.h"
#include "reports/budget.h"
#include "reports/depth_audit_report.h"
#include "reports/depth_plot.h"
#include "reports/report.h"
#include "tests/run_binary.h"
#include "tests/temp_dir_test.h"

namespace va {
namespace {

namespace fs = std::filesystem;

constexpr double kC31 = 2147483647.0;
constexpr double kC32 = 4294967295.0;

const DepthFormatAudit &formatOf(const DepthAuditResult &r, DepthFormat f) {
    for (const DepthFormatAudit &a : r.formats)
        if (a.format == f) return a;
    ADD_FAILURE() << "format " << depthFormatInfo(f).name << " missing from the audit";
    return r.formats.front();
}

// The decade sample at depth d (which must be one of the decade depths).
const DepthResolutionSample &sampleAt(const DepthFormatAudit &a, double d) {
    for (const DepthResolutionSample &s : a.decades)
        if (s.depth == d) return s;
    ADD_FAILURE() << a.name << ": no decade sample at " << d;
    return a.decades.front();
}

TEST(DepthAudit, DecadeDepthsAreNearPowersOfTenFar) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::f32});
    ASSERT_TRUE(r.error.empty()) << r.error;
    EXPECT_EQ(r.decadeDepths, (std::vector<double>{0.1, 1, 10, 100, 1000, 10000}));
    // Ends that are not powers of ten, and ends that are (never listed twice).
    EXPECT_EQ(auditDepthFormats(0.5, 20, {DepthFormat::f32}).decadeDepths, (std::vector<double>{0.5, 1, 10, 20}));
    EXPECT_EQ(auditDepthFormats(1, 100, {DepthFormat::f32}).decadeDepths, (std::vector<double>{1, 10, 100}));
    EXPECT_EQ(auditDepthFormats(2, 3, {DepthFormat::f32}).decadeDepths, (std::vector<double>{2, 3}));
}

TEST(DepthAudit, Uint32InvResolutionIsDSquaredOverTwoToThe32Minus1) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::uint32_inv});
    ASSERT_TRUE(r.error.empty()) << r.error;
    const DepthFormatAudit &a = r.formats[0];
    for (double d : {100.0, 1000.0, 10000.0}) {
        const DepthResolutionSample &s = sampleAt(a, d);
        ASSERT_TRUE(s.resolution.has_value()) << d;
        // Hand: v = floor(C/d); the next value towards far is v - 1; representative depths C/(v +- 1/2)
        // are 1/((v - 1/2)(v + 1/2)) C apart, and C/v^2 = d^2/C to first order.
        const double v = std::floor(kC32 / d);
        EXPECT_EQ(s.stored, v);
        EXPECT_NEAR(*s.resolution, kC32 / ((v - 0.5) * (v + 0.5)), 1e-14 * *s.resolution) << d;
        EXPECT_NEAR(*s.resolution / (d * d / kC32), 1.0, 1e-3) << d;
        ASSERT_TRUE(s.closedForm.has_value());
        EXPECT_EQ(*s.closedForm, d * d / kC32);
        EXPECT_LT(std::fabs(*s.relativeDifference), 1e-3);
    }
}

TEST(DepthAudit, Unorm24AtFarMatchesClosedForm) {
    const double n = 0.1, f = 1000, S = 16777215.0;
    const auto r = auditDepthFormats(n, f, {DepthFormat::unorm24});
    ASSERT_TRUE(r.error.empty()) << r.error;
    const DepthResolutionSample &s = sampleAt(r.formats[0], f);
    // At far the stored value is S, the last one: the step is to the previous value S - 1.
    EXPECT_EQ(s.stored, S);
    EXPECT_FALSE(s.stepToNext.has_value());
    ASSERT_TRUE(s.stepToPrev.has_value() && s.resolution.has_value() && s.closedForm.has_value());
    // d(S) - d(S-1) with d(s) = S f n / ((S - s) f + s n):  f - S f n/(f + (S-1) n) = f (f - n)/(f + (S-1) n).
    const double exact = f * (f - n) / (f + (S - 1) * n);
    EXPECT_NEAR(*s.resolution, exact, 1e-12 * exact);
    // Closed form d^2 (f - n)/(S f n) at d = f: f (f - n)/(S n). Its ratio to the exact step is
    // S n / (f + (S-1) n) = 1/(1 + (f - n)/(S n)): the linearization error, 6e-4 here.
    const double closed = f * (f - n) / (S * n);
    EXPECT_NEAR(*s.closedForm, closed, 1e-12 * closed);
    const double linearization = (f - n) / (S * n);
    EXPECT_NEAR(*s.relativeDifference, 1 / (1 + linearization) - 1, 1e-9);
    EXPECT_LT(std::fabs(*s.relativeDifference), 1.01 * linearization);
}

TEST(DepthAudit, LinearF32AtThousandIsTheFloatUlp) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::linear_f32});
    const DepthResolutionSample &s = sampleAt(r.formats[0], 1000);
    // 1000 is in [512, 1024) = [2^9, 2^10): the float spacing there is 2^(9-23) = 2^-14.
    ASSERT_TRUE(s.resolution.has_value());
    EXPECT_EQ(*s.resolution, std::ldexp(1.0, -14));
    EXPECT_EQ(*s.stepToPrev, std::ldexp(1.0, -14));
    EXPECT_EQ(*s.closedForm, std::ldexp(1.0, -14));
    EXPECT_EQ(*s.relativeDifference, 0.0);
    // The interval of doubles that round to 1000.0f: [1000 - 2^-15, 1000 + 2^-15] (ties go to the
    // even 1000), whose width in doubles is 2^-14 plus one double.
    EXPECT_NEAR(*s.bucketWidth, std::ldexp(1.0, -14), 1e-12);
    // At d = 1 = 2^0 the float below is twice as close: towards near the step is 2^-24, towards far 2^-23.
    const DepthResolutionSample &one = sampleAt(r.formats[0], 1);
    EXPECT_EQ(*one.stepToNext, std::ldexp(1.0, -23));
    EXPECT_EQ(*one.stepToPrev, std::ldexp(1.0, -24));
}

TEST(DepthAudit, DistinctValuesAreExactCounts) {
    const auto r = auditDepthFormats(0.1, 1000, allDepthFormats());
    ASSERT_TRUE(r.error.empty()) << r.error;
    // unorm16 stores 0 at near and 65535 at far: all 2^16 values.
    EXPECT_EQ(formatOf(r, DepthFormat::unorm16).distinctValues, 65536u);
    EXPECT_EQ(formatOf(r, DepthFormat::unorm24).distinctValues, 16777216u);
    // f32_reversed: 1.0f at near, 0.0f at far: every float in [0, 1], whose bit patterns run
    // 0 .. 0x3F800000. f32 spans the same floats the other way.
    EXPECT_EQ(formatOf(r, DepthFormat::f32_reversed).distinctValues, 0x3F800000u + 1u);
    EXPECT_EQ(formatOf(r, DepthFormat::f32).distinctValues, 0x3F800000u + 1u);
    // uint32_inv clamps below d = 1 (stored 2^32-1) and stores floor(C/1000) = 4294967 at far.
    EXPECT_EQ(formatOf(r, DepthFormat::uint32_inv).distinctValues, uint64_t(4294967295u - 4294967u + 1u));
    // linear_f32: floats from 0.1f to 1000.0f inclusive, by bit pattern.
    EXPECT_EQ(formatOf(r, DepthFormat::linear_f32).distinctValues, uint64_t(0x447A0000u - 0x3DCCCCCDu + 1u));
}

TEST(DepthAudit, RangeSaysWhatIntegerInverseFormatsCannotStore) {
    const auto r = auditDepthFormats(0.1, 1000, allDepthFormats());
    for (DepthFormat f : {DepthFormat::int31_inv, DepthFormat::uint32_inv}) {
        const DepthFormatAudit &a = formatOf(r, f);
        EXPECT_EQ(a.representableNear, 1.0) << a.name;
        EXPECT_EQ(a.representableFar, 1000.0) << a.name;
        EXPECT_NE(a.rangeNote.find("below 1"), std::string::npos) << a.rangeNote;
        const DepthResolutionSample &s = sampleAt(a, 0.1);
        EXPECT_FALSE(s.inRange);
        EXPECT_FALSE(s.resolution.has_value());
        EXPECT_TRUE(sampleAt(a, 1).inRange);
    }
    for (DepthFormat f : {DepthFormat::f32, DepthFormat::uint32_inv1, DepthFormat::unorm16}) {
        const DepthFormatAudit &a = formatOf(r, f);
        EXPECT_EQ(a.representableNear, 0.1) << a.name;
        EXPECT_TRUE(a.rangeNote.empty()) << a.name << ": " << a.rangeNote;
    }
}

// Property test over wide magnitudes (seeded): for every format, depths log-uniform over several
// [near, far] pairs: the inverse round-trips, storedFromKey inverts the key, and the
// cancellation-free difference agrees with the plain difference where that one is accurate.
TEST(DepthAudit, InversesRoundTripForEveryFormat) {
    std::mt19937_64 rng(20240611);
    const std::pair<double, double> ranges[] = {{0.1, 1000}, {0.001, 1e6}, {0.5, 20}, {1e-3, 10}, {10, 1e5}};
    for (DepthFormat fmt : allDepthFormats()) {
        for (auto [n, f] : ranges) {
            const DepthEncoder e = makeDepthEncoder(fmt, n, f);
            std::uniform_real_distribution<double> u(std::log(n), std::log(f));
            int failures = 0, checked = 0;
            for (int i = 0; i < 20000; ++i) {
                const double d = std::exp(u(rng));
                bool oor = false;
                const double v = depthStoredValue(e, d, &oor);
                if (oor) continue;
                ++checked;
                const double back = depthStoredValue(e, depthFromStored(e, v));
                if (back != v && failures++ < 3)
                    ADD_FAILURE() << depthFormatInfo(fmt).name << " [" << n << ", " << f << "] d=" << d
                                  << " stored " << v << " inverse " << depthFromStored(e, v) << " re-encodes to " << back;
                EXPECT_EQ(storedFromKey(e, depthKey(e, d)), v);
                // Two depths 1.5x apart: the plain difference of the inverses loses at most a few ulps
                // of d, a relative 1e-15 of the difference; the common-denominator form must agree.
                const double d2 = std::min(d * 1.5, f);
                if (d2 <= d) continue;
                const double v2 = depthStoredValue(e, d2);
                const double plain = depthFromStored(e, v2) - depthFromStored(e, v);
                if (plain > 0) {
                    EXPECT_NEAR(depthBetweenStored(e, v, v2), plain, 1e-9 * plain) << depthFormatInfo(fmt).name;
                }
            }
            EXPECT_EQ(failures, 0) << depthFormatInfo(fmt).name << " [" << n << ", " << f << "]";
            EXPECT_GT(checked, 1000) << depthFormatInfo(fmt).name;
        }
    }
}

TEST(DepthAudit, DecalOneMillimeterAboveFloorAtHundredMeters) {
    // near 0.1, far 1000: unorm16's step at 100 m is d^2 (f-n)/(S f n) = 1.5 m, so a decal 1 mm
    // above the floor shares the floor's stored value; f32_reversed's step there is about 1e-5 m.
    const DepthEncoder u16 = makeDepthEncoder(DepthFormat::unorm16, 0.1, 1000);
    const DepthEncoder rev = makeDepthEncoder(DepthFormat::f32_reversed, 0.1, 1000);
    EXPECT_TRUE(depthFormatFights(u16, 100, 0.001));
    EXPECT_FALSE(depthFormatFights(rev, 100, 0.001));
    const auto r = auditDepthFormats(0.1, 1000, {DepthFormat::unorm16, DepthFormat::f32_reversed});
    ASSERT_EQ(r.formats[0].fights.size(), 2u);
    EXPECT_EQ(r.formats[0].fights[1].gap, 0.001);
    ASSERT_TRUE(r.formats[0].fights[1].onset.has_value());
    EXPECT_LT(*r.formats[0].fights[1].onset, 100.0);
    EXPECT_FALSE(r.formats[1].fights[0].onset.has_value());  // 1 cm: never
    EXPECT_FALSE(r.formats[1].fights[1].onset.has_value());  // 1 mm: never
    EXPECT_FALSE(r.formats[1].fights[1].likely.has_value());
}

TEST(DepthAudit, FightDistanceIsAnOnsetAboveTheAnalyticBound) {
    const double n = 0.1, f = 10000;
    const auto r = auditDepthFormats(n, f, allDepthFormats());
    for (const DepthFormatAudit &a : r.formats) {
        const DepthEncoder e = makeDepthEncoder(a.format, n, f);
        for (const DepthFightDistance &fd : a.fights) {
            if (!fd.onset) continue;
            const double D = *fd.onset, g = fd.gap;
            ASSERT_TRUE(fd.onsetBucket.has_value()) << a.name;
            const double W = *fd.onsetBucket;
            EXPECT_GT(W, g) << a.name;
            // A pair inside the onset's bucket fights: centered in it, both surfaces stay (W - g)/2
            // inside its ends. The encoder's ends sit within a few ulps of depth of the exact ones
            // (its double arithmetic rounds C/d, z, ...): where (W - g)/2 is not clear of 8 ulps of
            // D, the bucket ties with the gap and either answer is the double arithmetic's.
            const double ulpD = std::nextafter(D, INFINITY) - D;
            if ((W - g) / 2 > 8 * ulpD) {
                EXPECT_TRUE(depthFormatFights(e, D + (W - g) / 2, g)) << a.name << " gap " << g;
            }
            // The buckets before it are no wider than the gap: the one half a gap nearer (clear of
            // the boundary by far more than the encoder's ulps).
            if (D - g / 2 > a.representableNear) {
                const auto prev = depthBucketAt(e, D - g / 2);
                ASSERT_TRUE(prev.has_value()) << a.name;
                EXPECT_LE(prev->width, g) << a.name << " gap " << g;
                EXPECT_LT(prev->key, depthKey(e, D + W / 2)) << a.name;
            }
            EXPECT_GE(D, a.representableNear);
            EXPECT_LE(D + g, f * (1 + DBL_EPSILON));
            // Likely: at least twice the gap, never nearer than the onset.
            ASSERT_TRUE(fd.likely.has_value()) << a.name;
            EXPECT_GE(*fd.likely, D) << a.name;
            // Necessary conditions for a collapse (the stored values of d and d + g differ by < 1):
            //   uint32_inv: C/d - C/(d+g) < 1  <=>  d (d + g) > C g
            //   unorm16:    S (z(d+g) - z(d)) < 1  <=>  d (d + g) > S f n g / (f - n)
            double bound = 0;  // the necessary d (d + g) for this format, 0 if none is checked
            if (a.format == DepthFormat::uint32_inv) bound = kC32 * g;
            if (a.format == DepthFormat::int31_inv) bound = kC31 * g;
            if (a.format == DepthFormat::unorm16) bound = 65535.0 * f * n * g / (f - n);
            EXPECT_GT(D * (D + g), bound * (1 - 1e-9)) << a.name << " gap " << g;
        }
    }
    // Formats whose step at far is below 1 mm never fight; those above 1 cm by far do.
    EXPECT_FALSE(formatOf(r, DepthFormat::f32_reversed_inf).fights[1].onset.has_value());
    EXPECT_TRUE(formatOf(r, DepthFormat::unorm24).fights[0].onset.has_value());
}

TEST(DepthAudit, WideRangeIsFiniteEverywhere) {
    const auto r = auditDepthFormats(1e-3, 1e6, allDepthFormats());
    ASSERT_TRUE(r.error.empty()) << r.error;
    ASSERT_EQ(r.formats.size(), size_t(kDepthFormatCount));
    ASSERT_EQ(r.decadeDepths.size(), 10u);
    for (const DepthFormatAudit &a : r.formats) {
        EXPECT_GT(a.distinctValues, 0u);
        for (const DepthResolutionSample &s : a.decades) {
            EXPECT_TRUE(std::isfinite(s.stored)) << a.name << " d=" << s.depth;
            if (!s.inRange) continue;
            ASSERT_TRUE(s.resolution.has_value()) << a.name << " d=" << s.depth;
            EXPECT_TRUE(std::isfinite(*s.resolution) && *s.resolution > 0) << a.name << " d=" << s.depth;
            ASSERT_TRUE(s.closedForm.has_value()) << a.name;
            EXPECT_TRUE(std::isfinite(*s.closedForm)) << a.name;
            ASSERT_TRUE(s.bucketWidth.has_value()) << a.name;
            EXPECT_GT(*s.bucketWidth, 0) << a.name << " d=" << s.depth;
        }
        for (const std::optional<double> &c : a.curveResolution)
            EXPECT_TRUE(!c || (std::isfinite(*c) && *c > 0)) << a.name;
        for (const DepthFightDistance &fd : a.fights) {
            EXPECT_TRUE(!fd.onset || std::isfinite(*fd.onset)) << a.name;
            EXPECT_TRUE(!fd.likely || std::isfinite(*fd.likely)) << a.name;
        }
    }
    const std::string table = depthAuditTable(r);
    EXPECT_EQ(table.find("nan"), std::string::npos) << table;
    EXPECT_EQ(table.find(" inf"), std::string::npos) << table;  // (f32_reversed_inf has "_inf")
    EXPECT_EQ(table.find("-inf"), std::string::npos) << table;
}

TEST(DepthAudit, DoubleInputLimitIsFlagged) {
    // f32 at near stores 0.0f; the next float a double depth reaches is f ulp(n) / (n (f - n)),
    // about 1.4e-16, not the subnormal 2^-149, so the step is one double ulp of near.
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::f32});
    const DepthResolutionSample &s = sampleAt(r.formats[0], 0.1);
    EXPECT_TRUE(s.skipsValues);
    const double ulpNear = std::nextafter(0.1, 1.0) - 0.1;
    EXPECT_NEAR(*s.resolution, ulpNear, 0.01 * ulpNear);
    EXPECT_FALSE(sampleAt(r.formats[0], 10).skipsValues);
}

TEST(DepthAudit, BadInputIsRefusedWithTheValueAndAFix) {
    std::string err;
    EXPECT_FALSE(validateDepthAuditRange(0, 100, &err));
    EXPECT_EQ(err, "near plane 0 must be a finite distance >= 1.2e-38 (the smallest normal float); use e.g. --near 0.1");
    EXPECT_FALSE(validateDepthAuditRange(-1, 100, &err));
    EXPECT_FALSE(validateDepthAuditRange(NAN, 100, &err));
    EXPECT_FALSE(validateDepthAuditRange(10, 10, &err));
    EXPECT_EQ(err, "far plane 10 must be finite and greater than the near plane 10; use e.g. --far 1000");
    EXPECT_FALSE(validateDepthAuditRange(0.1, INFINITY, &err));
    EXPECT_FALSE(validateDepthAuditRange(0.1, 1e39, &err));
    EXPECT_NE(err.find("largest float"), std::string::npos);
    EXPECT_TRUE(validateDepthAuditRange(1e-3, 1e6, &err));

    auto r = auditDepthFormats(5, 1, allDepthFormats());
    EXPECT_FALSE(r.error.empty());
    EXPECT_TRUE(r.formats.empty());
    EXPECT_EQ(depthAuditTable(r), "error: " + r.error + "\n");
    EXPECT_EQ(depthAuditJson(r)["error"], r.error);
    r = auditDepthFormats(0.1, 100, {});
    EXPECT_EQ(r.error, "no depth formats to audit; pass at least one, e.g. --formats f32,f32_reversed");
    r = auditDepthFormats(0.1, 100, {DepthFormat::f32, DepthFormat::unorm16, DepthFormat::f32});
    EXPECT_EQ(r.error, "depth format 'f32' is listed twice; list it once");
    DepthAuditSettings s;
    s.fightGaps = {0.01, -1};
    EXPECT_EQ(auditDepthFormats(0.1, 100, {DepthFormat::f32}, s).error,
              "fight gap -1 must be a finite distance > 0, e.g. 0.01 (1 cm)");
}

TEST(DepthAudit, JsonKeysAndNullForNever) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::linear_f32, DepthFormat::uint32_inv});
    const nlohmann::ordered_json j = depthAuditJson(r);
    EXPECT_EQ(j["format"], "visaudit-depth-audit/1");
    EXPECT_EQ(j["tool"]["version"], VISAUDIT_VERSION);
    EXPECT_EQ(j["near"], 0.1);
    EXPECT_EQ(j["far"], 10000.0);
    EXPECT_EQ(j["decade_depths"].size(), 6u);
    EXPECT_EQ(j["curve_depths"].size(), 200u);
    ASSERT_EQ(j["formats"].size(), 2u);
    const auto &lin = j["formats"][0];
    EXPECT_EQ(lin["name"], "linear_f32");
    EXPECT_EQ(lin["nearer_is"], "smaller");
    EXPECT_TRUE(lin["distinct_values"].is_number_unsigned());
    EXPECT_EQ(lin["fight_distances"][0]["gap"], 0.01);
    EXPECT_TRUE(lin["fight_distances"][0]["onset"].is_null());  // never
    EXPECT_TRUE(lin["fight_distances"][0]["likely"].is_null());
    EXPECT_TRUE(lin["fight_distances"][0]["onset_bucket_width"].is_null());
    EXPECT_TRUE(lin["representable"]["note"].is_null());
    const auto &r1000 = lin["resolution"][4];
    EXPECT_EQ(r1000["depth"], 1000.0);
    EXPECT_EQ(r1000["resolution"], std::ldexp(1.0, -14));
    for (const char *k : {"depth", "in_range", "stored", "key", "resolution", "step_to_next", "step_to_prev",
                          "skips_values", "bucket_width", "closed_form", "relative_difference"})
        EXPECT_TRUE(r1000.contains(k)) << k;
    const auto &u32 = j["formats"][1];
    EXPECT_EQ(u32["nearer_is"], "larger");
    EXPECT_EQ(u32["representable"]["near"], 1.0);
    EXPECT_FALSE(u32["resolution"][0]["in_range"].get<bool>());
    EXPECT_TRUE(u32["resolution"][0]["resolution"].is_null());  // d = 0.1 < 1: out of range
    EXPECT_TRUE(u32["fight_distances"][0]["onset"].is_number());
    EXPECT_GT(u32["fight_distances"][0]["onset_bucket_width"].get<double>(), 0.01);
    EXPECT_GT(u32["fight_distances"][0]["likely"].get<double>(), u32["fight_distances"][0]["onset"].get<double>());
    EXPECT_TRUE(u32["curve_resolution"][0].is_null());
    // No NaN or infinity anywhere: the text form parses back as standard JSON.
    nlohmann::json parsed;
    EXPECT_NO_THROW(parsed = nlohmann::json::parse(j.dump()));
    EXPECT_EQ(parsed["formats"].size(), 2u);
}

TEST(DepthAudit, TableRows) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::unorm16, DepthFormat::uint32_inv, DepthFormat::linear_f32});
    const std::string t = depthAuditTable(r);
    EXPECT_NE(t.find("depth formats over [0.1, 10000] m"), std::string::npos) << t;
    for (const char *col : {"onset 1cm", "likely 1cm", "onset 1mm", "likely 1mm"})
        EXPECT_NE(t.find(col), std::string::npos) << col << "\n" << t;
    EXPECT_NE(t.find("d=10000"), std::string::npos) << t;
    // unorm16's row starts with its bits and its 65536 values, uint32_inv's range is d>=1 and its
    // d=0.1 cell is "-", linear_f32 never fights.
    EXPECT_NE(t.find("unorm16             16        65536  all"), std::string::npos) << t;
    EXPECT_NE(t.find("uint32_inv          32   4294537800  d>=1          -"), std::string::npos) << t;
    const size_t lin = t.find("linear_f32");
    ASSERT_NE(lin, std::string::npos);
    const std::string linRow = t.substr(lin, t.find('\n', lin) - lin);
    EXPECT_NE(linRow.find("never       never       never       never"), std::string::npos) << linRow;
}

struct TempDir {
    std::string path;
    TempDir() {
        std::string t = (fs::temp_directory_path() / "visaudit-depth-audit-XXXXXX").string();
        path = ::mkdtemp(t.data()) ? t : "";
    }
    ~TempDir() {
        std::error_code ec;
        if (!path.empty()) fs::remove_all(path, ec);
    }
};

TEST(DepthAudit, PlotIsWrittenWithCurvesWhereTheyMustBe) {
    TempDir dir;
    ASSERT_FALSE(dir.path.empty());
    const std::string path = dir.path + "/depth-resolution.png";
    // One format alone: every curve sample's pixel must carry its color.
    const auto one = auditDepthFormats(0.1, 10000, {DepthFormat::uint32_inv});
    std::string err;
    ASSERT_TRUE(writeDepthResolutionPlot(one, path, &err)) << err;
    ImageData img;
    ASSERT_TRUE(readImage(path, &img, &err)) << err;
    EXPECT_EQ(img.width, 1200);
    EXPECT_EQ(img.height, 800);
    ASSERT_EQ(img.channels(), 3);
    ASSERT_EQ(img.pixelType, "uint8");
    auto px = [&](int x, int y) {
        const size_t i = (size_t(y) * size_t(img.width) + size_t(x)) * 3;
        return Rgb8{img.u8[i], img.u8[i + 1], img.u8[i + 2]};
    };
    const DepthPlotLayout L = depthPlotLayout(one);
    const Rgb8 color = depthPlotColor(DepthFormat::uint32_inv);
    int checked = 0;
    for (size_t i = 0; i < one.curveDepths.size(); i += 20) {
        const auto &v = one.formats[0].curveResolution[i];
        if (!v) continue;  // below d = 1: no curve
        const int x = L.xOf(one.curveDepths[i]), y = L.yOf(*v);
        if (x <= L.left + 1 || x >= L.right - 1 || y <= L.top + 1 || y >= L.bottom - 1) continue;
        EXPECT_EQ(px(x, y), color) << "curve sample " << i << " at (" << x << ", " << y << ")";
        ++checked;
    }
    EXPECT_GE(checked, 5);
    // Below d = 1 there is no uint32_inv curve: the column at d = 0.3 holds no curve color.
    const int x03 = L.xOf(0.3);
    for (int y = L.top + 2; y < L.bottom - 1; ++y) EXPECT_NE(px(x03, y), color) << y;
    // Legend: the format's color appears right of the plot area.
    bool legend = false;
    for (int y = L.top; y < L.top + 30; ++y)
        for (int x = L.right + 10; x < img.width; ++x) legend |= px(x, y) == color;
    EXPECT_TRUE(legend);

    // All formats: the curve samples are non-background, and nothing but the PNG is left behind.
    const auto all = auditDepthFormats(0.1, 10000, allDepthFormats());
    ASSERT_TRUE(writeDepthResolutionPlot(all, path, &err)) << err;
    ASSERT_TRUE(readImage(path, &img, &err)) << err;
    const DepthPlotLayout LA = depthPlotLayout(all);
    for (const DepthFormatAudit &a : all.formats) {
        const auto &v = a.curveResolution[100];
        ASSERT_TRUE(v.has_value()) << a.name;
        EXPECT_NE(px(LA.xOf(all.curveDepths[100]), LA.yOf(*v)), kDepthPlotBackground) << a.name;
    }
    int files = 0;
    for (const auto &entry : fs::directory_iterator(dir.path)) {
        (void)entry;
        ++files;
    }
    EXPECT_EQ(files, 1);

    // Failures: an unwritable path and a failed audit return false with the path in the message.
    EXPECT_FALSE(writeDepthResolutionPlot(all, dir.path + "/missing/dir/p.png", &err));
    EXPECT_NE(err.find(dir.path + "/missing/dir/p.png"), std::string::npos) << err;
    EXPECT_FALSE(writeDepthResolutionPlot(auditDepthFormats(1, 0.5, allDepthFormats()), path, &err));
    EXPECT_NE(err.find("the audit failed"), std::string::npos) << err;
}

TEST(DepthAudit, PlotColorsAreDistinct) {
    const auto &all = allDepthFormats();
    for (size_t i = 0; i < all.size(); ++i)
        for (size_t j = i + 1; j < all.size(); ++j) {
            const Rgb8 a = depthPlotColor(all[i]), b = depthPlotColor(all[j]);
            const int dist = std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b);
            EXPECT_GT(dist, 60) << depthFormatInfo(all[i]).name << " vs " << depthFormatInfo(all[j]).name;
            EXPECT_NE(a, kDepthPlotBackground);
        }
}

// ---- Exact fight distances ------------------------------------------------------------------------

// "%.5g", as the table prints the fight distances.
std::string g5(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.5g", v);
    return b;
}

// The onsets the issue quotes, derived here independently of the audit's bucket model.
//
// unorm24 stores v = round(S z), z = f(d-n)/(d(f-n)), S = 2^24 - 1. Value v holds the depths whose
// S z lies in [v - 1/2, v + 1/2). With D(s) = (S - s) f + s n the depth at S z = s is
// d(s) = S f n / D(s), so v's bucket is [d(v - 1/2), d(v + 1/2)), of width
//     W(v) = d(v + 1/2) - d(v - 1/2) = S f n (f - n) / (D(v - 1/2) D(v + 1/2))
// (the two D's differ by f - n), growing with v. To first order W = d^2 (f - n)/(S f n), so the
// first bucket wider than g starts near d* = sqrt(g S f n / (f - n)):
//     n = 0.1, f = 1e4, g = 0.01:   d* = sqrt(0.01 * 16777215 * 0.1 * 1.00001) = 129.529 m
//     g = 0.001:                    d* = sqrt(1677.74)                          =  40.961 m
// With f = 1e7, f/(f - n) = 1 + 1e-8 leaves both the same to 5 digits: 129.53 m and 40.96 m. The
// exact onset is d(v* - 1/2) for the first v* with W(v*) > g: the test walks v over a window
// around S z(d*) in long double and compares with the audit to 12 digits.
//
// f32 stores the float nearest to z. In [0.5, 1) floats are 2^-24 apart, so float x = 1 - j 2^-24
// holds z in [x - 2^-25, x + 2^-25): unorm24's buckets with 1/S replaced by 2^-24 (a relative
// 6e-8 narrower), so the same onsets to 5 digits; walked exactly too.
TEST(DepthAudit, ExactOnsetsOfUnorm24AndF32) {
    using LD = long double;
    const LD S = 16777215.0L;
    for (const double f : {1e4, 1e7}) {
        const double n = 0.1;
        const auto r = auditDepthFormats(n, f, {DepthFormat::unorm24, DepthFormat::f32});
        ASSERT_TRUE(r.error.empty()) << r.error;
        for (size_t gi = 0; gi < 2; ++gi) {
            const double g = r.fightGaps[gi];
            const char *quoted = gi == 0 ? "129.53" : "40.96";
            const LD dStar = std::sqrt(LD(g) * S * f * n / (f - n));
            // unorm24: walk v from below d*'s value upwards to the first bucket wider than g.
            auto D = [&](LD s) { return (S - s) * f + s * n; };
            auto W = [&](LD v) { return S * f * n * (f - n) / (D(v - 0.5L) * D(v + 0.5L)); };
            const LD zStar = f * (dStar - n) / (dStar * (f - n));
            LD v = std::floor(S * zStar) - 50;
            ASSERT_LE(W(v), g);
            while (!(W(v) > g)) v += 1;
            const double expectUnorm = double(S * f * n / D(v - 0.5L));
            const DepthFightDistance &fu = formatOf(r, DepthFormat::unorm24).fights[gi];
            ASSERT_TRUE(fu.onset.has_value());
            EXPECT_NEAR(*fu.onset, expectUnorm, 1e-12 * expectUnorm) << "unorm24 far " << f << " gap " << g;
            EXPECT_EQ(g5(*fu.onset), quoted) << "unorm24 far " << f;
            EXPECT_NEAR(*fu.onsetBucket, double(W(v)), 1e-9 * g);
            // f32: floats x = 1 - j 2^-24 nearer to 1 are deeper; walk j downwards (deeper).
            const LD u = std::ldexp(1.0L, -24);
            auto dz = [&](LD z) { return f * n / (f * (1 - z) + z * n); };
            auto Wf = [&](LD j) { return dz(1 - j * u + u / 2) - dz(1 - j * u - u / 2); };
            LD j = std::ceil((1 - zStar) / u) + 50;
            ASSERT_LE(Wf(j), g);
            while (!(Wf(j) > g)) j -= 1;
            const double expectF32 = double(dz(1 - j * u - u / 2));
            const DepthFightDistance &ff = formatOf(r, DepthFormat::f32).fights[gi];
            if (f == 1e4) {
                ASSERT_TRUE(ff.onset.has_value());
                EXPECT_NEAR(*ff.onset, expectF32, 1e-12 * expectF32) << "f32 gap " << g;
                EXPECT_EQ(g5(*ff.onset), quoted) << "f32";
            }
        }
    }
    // The table prints them.
    const std::string t = depthAuditTable(auditDepthFormats(0.1, 10000, {DepthFormat::unorm24}));
    EXPECT_NE(t.find("129.53"), std::string::npos) << t;
    EXPECT_NE(t.find("40.96"), std::string::npos) << t;
}

// Likely: the first bucket at least twice the gap wide. For unorm24, W ~ d^2 (f - n)/(S f n) gives
// sqrt(2) times the onset: 183.18 m for 1 cm.
TEST(DepthAudit, LikelyIsWhereBucketsReachTwiceTheGap) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::unorm24, DepthFormat::uint32_inv});
    const DepthFightDistance &fd = formatOf(r, DepthFormat::unorm24).fights[0];
    ASSERT_TRUE(fd.onset && fd.likely);
    EXPECT_NEAR(*fd.likely / *fd.onset, std::sqrt(2.0), 1e-3);
    const DepthEncoder e = makeDepthEncoder(DepthFormat::unorm24, 0.1, 10000);
    const auto at = depthBucketAt(e, *fd.likely + 1e-6);
    ASSERT_TRUE(at.has_value());
    EXPECT_GE(at->width, 0.02);
    EXPECT_LT(depthBucketAt(e, *fd.likely - 0.01)->width, 0.02);
    // uint32_inv: buckets C/(v (v + 1)) ~ d^2/C: onset sqrt(C g), likely sqrt(2 C g).
    const DepthFightDistance &u = formatOf(r, DepthFormat::uint32_inv).fights[0];
    EXPECT_NEAR(*u.onset, std::sqrt(kC32 * 0.01), 0.02);
    EXPECT_NEAR(*u.likely, std::sqrt(2 * kC32 * 0.01), 0.02);
}

// A brute-force bucket walk, independent of the bucket model: from a start depth, the encoder's
// buckets one after the other (each end found by bisecting depthKey over the doubles), at most
// `count` of them, the last cut at hi.
struct WalkedBucket {
    double start = 0, width = 0;
    uint32_t key = 0;
};
std::vector<WalkedBucket> walkBuckets(const DepthEncoder &e, double start, double hi, int count) {
    auto bits = [](double x) {
        uint64_t u;
        std::memcpy(&u, &x, 8);
        return u;
    };
    auto fromBits = [](uint64_t u) {
        double x;
        std::memcpy(&x, &u, 8);
        return x;
    };
    std::vector<WalkedBucket> out;
    double a = start;
    for (int i = 0; i < count; ++i) {
        const uint32_t k = depthKey(e, a);
        double end = hi;
        if (depthKey(e, hi) > k) {  // the first double past a whose key is larger
            uint64_t lo = bits(a), up = bits(hi);
            while (up - lo > 1) {
                const uint64_t m = lo + (up - lo) / 2;
                if (depthKey(e, fromBits(m)) > k) up = m;
                else lo = m;
            }
            end = fromBits(up);
        }
        out.push_back({a, end - a, k});
        if (end >= hi) break;
        a = end;
    }
    return out;
}

// Property test (seeded): for every format and log24:C=0.001, random near/far over 1e-3 .. 1e8
// and a random start depth; the walk takes up to 2500 buckets from there, and the gap is set just
// below the width of a random one of them (by a relative 1e-6 .. 0.1), so that a first bucket
// wider than the gap exists among those walked: it may be that one or any before it (float
// formats' buckets shrink at a binade). The audit's onset from the same start must be that first
// walked bucket: the same key, the same start to within the ulps of depth by which the encoder's
// double arithmetic moves a bucket's end.
TEST(DepthAudit, OnsetMatchesABruteForceBucketWalk) {
    std::mt19937_64 rng(1919);
    std::uniform_real_distribution<double> U(0, 1);
    std::vector<DepthFormatSpec> formats(allDepthFormats().begin(), allDepthFormats().end());
    formats.push_back({DepthFormat::log24, 0.001});
    int compared = 0, ties = 0;
    for (const DepthFormatSpec &fmt : formats) {
        for (int c = 0; c < 12; ++c) {
            const double n = std::pow(10.0, -3 + 4 * U(rng));
            const double f = std::min(n * std::pow(10.0, 1 + 6 * U(rng)), 1e8);
            const DepthEncoder e = makeDepthEncoder(fmt, n, f);
            double lo, hi;
            depthRepresentableRange(e, &lo, &hi, nullptr);
            if (!(hi > lo)) continue;  // int31_inv, uint32_inv with far < 1: nothing to store
            const double start = std::clamp(lo * std::pow(hi / lo, U(rng)), lo, hi);
            const std::vector<WalkedBucket> walk = walkBuckets(e, start, hi, 1 + int(2499 * U(rng)));
            const WalkedBucket &target = walk.back();
            // At least 64 ulps of depth: below that the double input, not the format, decides.
            const double ulpStart = std::nextafter(target.start, INFINITY) - target.start;
            const double g = target.width * (1 - std::pow(10.0, -5 + 4 * U(rng)));
            if (!(g > 64 * ulpStart)) continue;
            size_t first = 0;
            while (!(walk[first].width > g)) ++first;  // ends at the target at the latest
            const WalkedBucket &w = walk[first];
            const auto on = fightOnset(e, start, hi, g);
            const std::string what = depthFormatName(fmt) + " n=" + std::to_string(n) + " f=" + std::to_string(f) +
                                     " start=" + std::to_string(start) + " g=" + std::to_string(g) + " bucket " +
                                     std::to_string(first) + " of " + std::to_string(walk.size());
            ASSERT_TRUE(on.has_value()) << what;
            // The encoder's ends lie near the exact ones: within 8 ulps of the end's depth, plus the
            // rounding of what it computes before its last rounding, measured in stored steps: C/d
            // in double is off by up to (C/d) 2^-53 <= 2^32 2^-53 = 5e-7 of a step (the integer
            // 1/d formats), z or z_ndc by about 2^-52 against a 2^-24 step (4e-9); log24's C d + 1
            // by half its double spacing, ulp(C d + 1)/(2C) of depth. A bucket whose width is that
            // close to the gap is a tie either may count.
            const double end = w.start + w.width;
            const DepthFormat k = fmt.format;
            const bool inverse = k == DepthFormat::int31_inv || k == DepthFormat::uint32_inv || k == DepthFormat::uint32_inv1;
            const double steps = inverse ? 4 * (kC32 / end) * std::ldexp(1.0, -53) : 1e-8;  // of a step
            double tol = 8 * (std::nextafter(end, INFINITY) - end) + steps * w.width;
            if (fmt.format == DepthFormat::log24) {
                const double x = fmt.logC * end + 1;
                tol += 2 * (std::nextafter(x, INFINITY) - x) / fmt.logC;
            }
            bool tie = false;
            for (size_t i = 0; i <= first; ++i) tie |= std::fabs(walk[i].width - g) <= 2 * tol;
            if (tie) {
                ++ties;
                continue;
            }
            ++compared;
            EXPECT_EQ(on->key, w.key) << what;
            EXPECT_NEAR(on->depth, w.start, tol) << what;
            EXPECT_NEAR(on->width, w.width, 2 * tol) << what;
        }
    }
    // Seed 1919: 215 compared, 12 ties (buckets that grow by a relative 1e-7 each put several
    // within the tolerance of a gap set a relative 1e-5 below one of them).
    EXPECT_GE(compared, 150) << ties << " ties";
    EXPECT_LE(ties, 25);
}

// The floats that shrink with depth have saw-tooth buckets: widths grow within a binade of the
// stored value and halve at each power of two, so the first bucket wider than a gap can lie binades
// away from where widths first approach it. f32_reversed_inf stores v = float(n/d); a float v
// strictly inside a binade [2^-(j+1), 2^-j) (spacing u = 2^-(j+24)) holds z in [v - u/2, v + u/2),
// the depths (n/(v + u/2), n/(v - u/2)], of width n u/(v^2 - u^2/4): growing as v falls. The power
// of two p = 2^-j holds z in [p - u/2, p + u) (twice the spacing above it), width
// n/(p - u/2) - n/(p + u). In depth order (v falling) the first bucket wider than g in binade j is
// the largest v with v^2 - u^2/4 < n u/g. Walking the binades and their powers of two in order
// gives the exact onset, which the audit's binade walk must reproduce.
TEST(DepthAudit, SawToothFloatsOnsetAcrossBinades) {
    using LD = long double;
    for (const double g : {0.05, 0.013, 0.001}) {
        const double n = 1, f = 1e6;
        LD expect = -1;
        for (int j = 0; j < 60 && expect < 0; ++j) {
            const LD p = std::ldexp(1.0L, -j), u = std::ldexp(1.0L, -(j + 24));
            // The power of two p (j = 0: z = 1 at near, its bucket cut at near).
            const LD pw = n / (p - u / 2) - (j == 0 ? LD(n) : n / (p + u));
            if (pw > g) {
                expect = j == 0 ? LD(n) : n / (p + u);
                break;
            }
            // The interior (p/2, p), v falling from p - u to p/2 + u.
            const LD vmax = std::sqrt(n * u / g + u * u / 4);  // W(v) > g  <=>  v < vmax
            LD v = std::floor((std::min(vmax, p) - p / 2) / u) * u + p / 2;  // grid point <= vmax
            if (v >= vmax) v -= u;
            if (v > p / 2 && v < p) expect = n / (v + u / 2);
        }
        ASSERT_GT(expect, 0) << g;
        const DepthEncoder e = makeDepthEncoder(DepthFormat::f32_reversed_inf, n, f);
        const auto on = fightOnset(e, n, f, g);
        ASSERT_TRUE(on.has_value()) << g;
        EXPECT_NEAR(on->depth, double(expect), 1e-12 * double(expect)) << "gap " << g;
        // The bucket just before it is no wider than the gap.
        EXPECT_LE(depthBucketAt(e, on->depth * (1 - 1e-9))->width, g) << g;
    }
}

// ---- Published figures -------------------------------------------------------------------------

// Outerra's logarithmic depth buffer table: Brano Kemen, "Logarithmic Depth Buffer", Outerra blog,
// 2009-08-12. 24-bit buffer, far plane 10,000 km, resolution L (C x + 1)/((2^24 - 1) C) with
// L = ln(C far + 1) at distance x, for C = 1 and C = 0.001:
//     x        1 m      10 m     100 m    1 km    10 km   100 km  1 Mm   10 Mm
//     C = 1    1.9e-6   1.1e-5   9.7e-5   0.001   0.01    0.096   0.96   9.6
//     C=0.001  0.0005   0.0005   0.0006   0.001   0.006   0.055   0.549  5.49
// (printed to 1-3 digits; 0.00055 appears as 0.0005). The audit's measured step between stored
// values must match each to within one unit of its last printed digit, and `depth-audit --near 0.1
// --far 1e7` prints 1.92e-06, 0.00961 and 9.61 for log24 at 1 m, 10 km and 10,000 km.
TEST(DepthAudit, OuterraLogDepthTable) {
    const std::vector<double> xs = {1, 10, 100, 1e3, 1e4, 1e5, 1e6, 1e7};
    // {published value, one unit of its last printed digit}
    const std::vector<std::pair<double, double>> c1 = {{1.9e-6, 1e-7}, {1.1e-5, 1e-6}, {9.7e-5, 1e-6}, {0.001, 0.001},
                                                       {0.01, 0.01},   {0.096, 0.001}, {0.96, 0.01},  {9.6, 0.1}};
    const std::vector<std::pair<double, double>> c0001 = {{0.0005, 1e-4}, {0.0005, 1e-4}, {0.0006, 1e-4},
                                                          {0.001, 1e-3},  {0.006, 1e-3},  {0.055, 1e-3},
                                                          {0.549, 1e-3},  {5.49, 1e-2}};
    const auto r = auditDepthFormats(0.1, 1e7, std::vector<DepthFormatSpec>{DepthFormat::log24, {DepthFormat::log24, 0.001}});
    ASSERT_TRUE(r.error.empty()) << r.error;
    ASSERT_EQ(r.formats[1].name, "log24:C=0.001");
    for (size_t i = 0; i < xs.size(); ++i) {
        for (int k = 0; k < 2; ++k) {
            const DepthResolutionSample &s = sampleAt(r.formats[size_t(k)], xs[i]);
            ASSERT_TRUE(s.resolution.has_value()) << xs[i];
            const auto [pub, unit] = (k == 0 ? c1 : c0001)[i];
            EXPECT_LT(std::fabs(*s.resolution - pub), unit) << r.formats[size_t(k)].name << " at " << xs[i];
        }
    }
    const std::string t = depthAuditTable(auditDepthFormats(0.1, 1e7, {DepthFormat::log24}));
    const std::string row = t.substr(t.find("log24"));
    for (const char *cell : {"1.92e-06", "0.00961", "9.61"}) EXPECT_NE(row.find(cell), std::string::npos) << cell << "\n" << row;
}

// The WebGPU specification (gpuweb/gpuweb spec/index.bs, the depth24plus note under "Texture
// Formats"): depth24plus may be implemented as "24-bit depth" (unorm, "1 ULP has a constant value
// of 1/(2^24 - 1)") or as depth32float ("1 ULP has a variable value no greater than 1/(2^24)" over
// 0.0 to 1.0), and the float values are not a superset of the 24-bit ones. visaudit's depth24plus
// is the 24-bit one (unorm24's arithmetic) and its depth32float is f32's; check the spec's numbers
// on the stored values, and that the two implementations differ where the note says they can.
TEST(DepthAudit, WebGpuDepth24PlusAndDepth32FloatAsTheSpecDefinesThem) {
    const double n = 0.1, f = 1000;
    const DepthEncoder d24 = makeDepthEncoder(DepthFormat::depth24plus, n, f),
                       u24 = makeDepthEncoder(DepthFormat::unorm24, n, f),
                       d32 = makeDepthEncoder(DepthFormat::depth32float, n, f),
                       f32 = makeDepthEncoder(DepthFormat::f32, n, f);
    std::mt19937_64 rng(24);
    std::uniform_real_distribution<double> U(std::log(n), std::log(f));
    double maxUlp32 = 0;
    int differ = 0;
    for (int i = 0; i < 20000; ++i) {
        const double d = std::exp(U(rng));
        const double v24 = depthStoredValue(d24, d), v32 = depthStoredValue(d32, d);
        EXPECT_EQ(v24, depthStoredValue(u24, d));
        EXPECT_EQ(depthKey(d32, d), depthKey(f32, d));
        // 24-bit depth: consecutive values are 1/(2^24 - 1) apart in [0, 1].
        const double z24 = v24 / 16777215.0, next24 = (v24 + 1) / 16777215.0;
        EXPECT_EQ(v24, std::floor(v24));
        EXPECT_NEAR(next24 - z24, 1 / 16777215.0, 4e-16);  // two roundings of numbers below 1
        // depth32float: its spacing towards 1 is at most 2^-24.
        const float x = float(v32);
        if (x < 1.0f) maxUlp32 = std::max(maxUlp32, double(std::nextafter(x, 1.0f)) - double(x));
        // Not a superset: the 24-bit value is rarely a float (k/(2^24 - 1) has a repeating
        // binary fraction unless k is 0 or a multiple of 2^24 - 1).
        differ += double(float(z24)) != z24;
    }
    EXPECT_LE(maxUlp32, std::ldexp(1.0, -24));
    EXPECT_GT(differ, 19900);
}

// Outerra, "Maximizing Depth Buffer Range and Precision" (Brano Kemen, 2012): with the standard
// projection "half of the available range is packed into tiny distance from the near plane to
// twice the near plane distance". Exactly: z(2n) = f/(2(f - n)), so unorm24 stores
// round(S f/(2(f - n))) at 2n: half of its values, plus n/(f - n) of a half.
TEST(DepthAudit, HalfTheValuesLieBetweenNearAndTwiceNear) {
    for (const double f : {100.0, 1e4, 1e7}) {
        const double n = 0.1;
        const DepthEncoder e = makeDepthEncoder(DepthFormat::unorm24, n, f);
        const double share = double(depthKey(e, 2 * n) - depthKey(e, n)) / 16777215.0;
        EXPECT_GE(share, 0.5 - 1 / 16777215.0) << f;
        EXPECT_LE(share, 0.5 * (1 + n / (f - n)) + 1 / 16777215.0) << f;
    }
}

// vkQuake PR #336 ("Switch to reverse depth projection"): "Without a float depth buffer this just
// shifts around precision issues?" With exact arithmetic it does not even shift them: the
// reversed value is S (1 - z), the 24-bit grid is uniform in z, so every bucket is the same
// interval of depths. Every figure of unorm24_reversed is unorm24's (and unorm16's for 16 bits);
// what reversed-Z does change on an integer buffer is the float arithmetic before the conversion
// (a GPU's projection and divide), which these two formats leave out (docs/depth-formats.md).
TEST(DepthAudit, ReversedZOnAnIntegerBufferMovesNoBucket) {
    for (const auto &[n, f] : std::vector<std::pair<double, double>>{{0.1, 1e4}, {0.01, 1e6}, {1, 50}}) {
        const auto r = auditDepthFormats(n, f, {DepthFormat::unorm24, DepthFormat::unorm24_reversed,
                                                DepthFormat::unorm16, DepthFormat::unorm16_reversed});
        ASSERT_TRUE(r.error.empty()) << r.error;
        for (size_t p = 0; p < 4; p += 2) {
            const DepthFormatAudit &a = r.formats[p], &b = r.formats[p + 1];
            EXPECT_EQ(a.distinctValues, b.distinctValues);
            for (size_t i = 0; i < a.decades.size(); ++i) {
                ASSERT_EQ(a.decades[i].resolution.has_value(), b.decades[i].resolution.has_value());
                if (a.decades[i].resolution)
                    EXPECT_NEAR(*a.decades[i].resolution, *b.decades[i].resolution, 1e-9 * *a.decades[i].resolution)
                        << a.name << " at " << a.decades[i].depth;
            }
            for (size_t g = 0; g < a.fights.size(); ++g) {
                ASSERT_EQ(a.fights[g].onset.has_value(), b.fights[g].onset.has_value());
                if (a.fights[g].onset) EXPECT_NEAR(*a.fights[g].onset, *b.fights[g].onset, 1e-9 * *a.fights[g].onset);
            }
        }
        // Stored values mirror: v + v_reversed = S (up to a tie at a half-integer).
        const DepthEncoder u = makeDepthEncoder(DepthFormat::unorm24, n, f),
                           ur = makeDepthEncoder(DepthFormat::unorm24_reversed, n, f);
        for (double d = n; d < f; d *= 1.37)
            EXPECT_NEAR(depthStoredValue(u, d) + depthStoredValue(ur, d), 16777215.0, 1.0) << d;
    }
}

// Nathan Reed, "Depth Precision Visualized" (2015): with OpenGL's [-1, 1] z_ndc and no
// glClipControl, reversed-Z does not rescue a float buffer, because the far values gather at
// z_ndc = -1 where floats are as coarse as near 1, and the window transform 0.5 z + 0.5 adds
// that coarseness. In numbers: f32_gl_reversed's steps far away are exactly half of f32_gl's
// (z_ndc's 2^-24 spacing near -1 becomes 2^-25 in w: one bit), while f32_reversed, with the
// [0, 1] range, never fights at 1 mm up to 10 km.
TEST(DepthAudit, ReversedZWithoutClipControlGainsOneBit) {
    const auto r = auditDepthFormats(0.1, 10000, {DepthFormat::f32_gl, DepthFormat::f32_gl_reversed, DepthFormat::f32_reversed});
    for (double d : {100.0, 1000.0}) {
        const double std = *sampleAt(r.formats[0], d).resolution, rev = *sampleAt(r.formats[1], d).resolution;
        EXPECT_NEAR(rev / std, 0.5, 0.01) << d;
    }
    // Onsets: f32_gl 105.75 m (unorm24's 129.53 / sqrt(1.5): its window-depth buckets alternate 3
    // and 1 z_ndc floats, 1.5 and 0.5 of the mean), f32_gl_reversed sqrt(2) x 129.53 = 183.18 m.
    EXPECT_EQ(g5(*r.formats[0].fights[0].onset), "105.75");
    EXPECT_EQ(g5(*r.formats[1].fights[0].onset), "183.18");
    EXPECT_FALSE(r.formats[2].fights[1].onset.has_value());
}

// ---- Why a hotspot fights -------------------------------------------------------------------------

// Near 0.1, far 1e4, a hotspot at 200 m. Bucket widths there, in the cheapest-first order:
//   unorm16 d^2 (f-n)/(S f n) = 6.1 m, unorm24 0.0238 m (and their reversed, _gl, depth24plus alike),
//   log24 L (C d + 1)/(S C) = ln(10001) 201/(2^24 - 1) = 1.10e-4 m, int31_inv d^2/(2^31-1) = 1.86e-5,
//   f32 0.0238, f32_reversed ulp(z) d^2 (f-n)/(n f) with z = 4.9e-4 in [2^-11, 2^-10): 2^-34 4e5 = 2.33e-5,
//   linear_f32 ulp(200) = 1.53e-5, inv_f32 d^2 ulp(1/200) = 4e4 2^-31 = 1.86e-5,
//   uint32_inv d^2/(2^32-1) = 9.3e-6.
// So a 1 cm gap is first resolved by log24, a 1e-5 m gap by uint32_inv, 1e-9 m by none.
TEST(DepthAudit, HotspotSaysItsGapBucketAndCheapestFormat) {
    ZFightHotspot h;
    h.depth = 200;
    h.depthGap = 0.01;
    explainHotspot(0.1, 1e4, DepthFormatSpec(DepthFormat::unorm24), false, &h);
    ASSERT_TRUE(h.viewBucketWidth.has_value());
    EXPECT_NEAR(*h.viewBucketWidth, 200.0 * 200 * (1e4 - 0.1) / (16777215.0 * 1e4 * 0.1), 1e-5);
    ASSERT_TRUE(h.cheapestFormat.has_value());
    EXPECT_EQ(*h.cheapestFormat, DepthFormat::log24);
    EXPECT_NEAR(*h.cheapestBucketWidth, std::log(10001.0) * 201 / 16777215.0, 1e-7);
    EXPECT_NE(h.why.find("unorm24's stored-value bucket there is 0.0238 m wide, wider than the gap"), std::string::npos)
        << h.why;
    EXPECT_NE(h.why.find("log24 (24 bits"), std::string::npos) << h.why;

    h.depthGap = 1e-5;
    explainHotspot(0.1, 1e4, DepthFormatSpec(DepthFormat::unorm24), false, &h);
    ASSERT_TRUE(h.cheapestFormat.has_value());
    EXPECT_EQ(*h.cheapestFormat, DepthFormat::uint32_inv);

    h.depthGap = 1e-9;
    explainHotspot(0.1, 1e4, DepthFormatSpec(DepthFormat::unorm24), false, &h);
    EXPECT_FALSE(h.cheapestFormat.has_value());
    EXPECT_NE(h.why.find("every format's bucket there is wider than the gap"), std::string::npos) << h.why;

    h.depthGap = 0;
    explainHotspot(0.1, 1e4, DepthFormatSpec(DepthFormat::unorm24), true, &h);
    EXPECT_TRUE(h.coplanar);
    EXPECT_FALSE(h.cheapestFormat.has_value());
    EXPECT_EQ(h.why, "coplanar surfaces: no depth format can order them; offset one surface or use a depth bias");
    // Without a view format there is no view bucket; outside the format's range neither.
    explainHotspot(0.1, 1e4, std::nullopt, false, &h);
    EXPECT_FALSE(h.viewBucketWidth.has_value());
    h.depth = 0.5;
    explainHotspot(0.1, 1e4, DepthFormatSpec(DepthFormat::uint32_inv), false, &h);
    EXPECT_FALSE(h.viewBucketWidth.has_value());  // uint32_inv holds no depth below 1
}

TEST(DepthAudit, CheapestFirstOrderHoldsEveryFormatOnceByBits) {
    const auto &order = depthFormatsCheapestFirst();
    ASSERT_EQ(order.size(), size_t(kDepthFormatCount));
    for (size_t i = 1; i < order.size(); ++i)
        EXPECT_LE(depthFormatInfo(order[i - 1]).bits, depthFormatInfo(order[i]).bits) << depthFormatInfo(order[i]).name;
    for (DepthFormat f : allDepthFormats()) EXPECT_EQ(std::count(order.begin(), order.end(), f), 1);
}

// ---- New formats through the program: --depth-format, --zfight-formats, budgets -------------------

class DepthFormatsCli : public testing_util::TempDirTest {
  protected:
    DepthFormatsCli() : TempDirTest("depthfmt") {}
};

TEST_F(DepthFormatsCli, NewFormatsInAnalyzeAndCheck) {
    // The demo with every view in unorm24_reversed: the view's own row joins the default twelve.
    auto r = testing_util::runBinary({"analyze", "--depth-format", "unorm24_reversed", "--out", (dir_ / "a").string(),
                                      "--quiet"},
                                     dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    auto report = nlohmann::json::parse(testing_util::slurpFile(dir_ / "a" / "report.json"));
    for (const auto &v : report["views"]) {
        EXPECT_EQ(v["depth_format"], "unorm24_reversed");
        EXPECT_EQ(v["depth"]["formats"].size(), 13u);
        EXPECT_TRUE(v["depth"]["formats"].contains("unorm24_reversed"));
        for (const auto &h : v["depth"]["hotspots"]) {
            EXPECT_TRUE(h.contains("view_bucket_width") && h.contains("cheapest_format") && h.contains("why")) << h;
            EXPECT_FALSE(h["why"].get<std::string>().empty());
        }
    }
    // log24 with its constant as a parameter, and every format evaluated.
    r = testing_util::runBinary({"analyze", "--depth-format", "log24:C=0.01", "--zfight-formats", "all", "--out",
                                 (dir_ / "b").string(), "--quiet"},
                                dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    report = nlohmann::json::parse(testing_util::slurpFile(dir_ / "b" / "report.json"));
    EXPECT_EQ(report["views"][0]["depth_format"], "log24:C=0.01");
    EXPECT_EQ(report["views"][0]["depth"]["formats"].size(), size_t(kDepthFormatCount) + 1);
    // Bad values: a clear message and exit 2.
    r = testing_util::runBinary({"analyze", "--depth-format", "log24:C=-1", "--out", (dir_ / "c").string()}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("C must be a finite number > 0, e.g. log24:C=0.001"), std::string::npos) << r.err;
    r = testing_util::runBinary({"analyze", "--zfight-formats", "f32,f32", "--out", (dir_ / "c").string()}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--zfight-formats: depth format 'f32' is listed twice"), std::string::npos) << r.err;

    // A budget naming opt-in formats: check evaluates them (depth24plus: both implementations).
    const fs::path budget = dir_ / "budget.json";
    std::ofstream(budget) << R"({"format": "visaudit-budget/1", "limits": {"min_depth_format": "depth24plus"}})";
    r = testing_util::runBinary({"check", "--budget", budget.string(), "--out", (dir_ / "d").string(), "--quiet"}, dir_);
    EXPECT_TRUE(r.code == 0 || r.code == 1) << r.err;
    EXPECT_NE(r.out.find("in depth24plus (24-bit and depth32float)"), std::string::npos) << r.out;
    report = nlohmann::json::parse(testing_util::slurpFile(dir_ / "d" / "report.json"));
    EXPECT_TRUE(report["views"][0]["depth"]["formats"].contains("depth24plus"));
    EXPECT_TRUE(report["views"][0]["depth"]["formats"].contains("depth32float"));
}

TEST(DepthAudit, BudgetDepthFormatsNameWhatCheckMustEvaluate) {
    Budget b;
    b.limits["min_depth_format"] = "depth24plus";
    b.views["hall"]["min_depth_format"] = "log24:C=0.5";
    b.views["atrium"]["overdraw"] = 3;
    const std::vector<DepthFormatSpec> fs = budgetDepthFormats(b);
    ASSERT_EQ(fs.size(), 3u);
    EXPECT_EQ(fs[0], DepthFormatSpec(DepthFormat::depth24plus));
    EXPECT_EQ(fs[1], DepthFormatSpec(DepthFormat::depth32float));
    EXPECT_EQ(fs[2], DepthFormatSpec(DepthFormat::log24, 0.5));
}

}  // namespace
}  // namespace va
