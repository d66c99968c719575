// The depth-format audit (analysis/depth_audit.h), its table and JSON, and its plot: hand-computed
// resolutions, exact distinct-value counts, inverse round trips over wide magnitudes, fight
// predicates and onsets against analytic bounds, bad input, and the PNG read back through OIIO.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "analysis/depth_audit.h"
#include "reports/depth_audit_report.h"
#include "reports/depth_plot.h"
#include "reports/report.h"

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
    ASSERT_TRUE(r.formats[0].fights[1].distance.has_value());
    EXPECT_LT(*r.formats[0].fights[1].distance, 100.0);
    EXPECT_FALSE(r.formats[1].fights[0].distance.has_value());  // 1 cm: never
    EXPECT_FALSE(r.formats[1].fights[1].distance.has_value());  // 1 mm: never
}

TEST(DepthAudit, FightDistanceIsAnOnsetAboveTheAnalyticBound) {
    const double n = 0.1, f = 10000;
    const auto r = auditDepthFormats(n, f, allDepthFormats());
    for (const DepthFormatAudit &a : r.formats) {
        const DepthEncoder e = makeDepthEncoder(a.format, n, f);
        for (const DepthFightDistance &fd : a.fights) {
            if (!fd.distance) continue;
            const double D = *fd.distance, g = fd.gap;
            // The reported depth fights, and (bisection) the double just below it does not, unless
            // it is the start of the representable range.
            EXPECT_TRUE(depthFormatFights(e, D, g)) << a.name << " gap " << g;
            if (D > a.representableNear) {
                EXPECT_FALSE(depthFormatFights(e, std::nextafter(D, 0.0), g)) << a.name;
            }
            EXPECT_GE(D, a.representableNear);
            EXPECT_LE(D + g, f * (1 + DBL_EPSILON));
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
    EXPECT_FALSE(formatOf(r, DepthFormat::f32_reversed_inf).fights[1].distance.has_value());
    EXPECT_TRUE(formatOf(r, DepthFormat::unorm24).fights[0].distance.has_value());
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
        for (const DepthFightDistance &fd : a.fights)
            EXPECT_TRUE(!fd.distance || std::isfinite(*fd.distance)) << a.name;
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
    EXPECT_TRUE(lin["fight_distances"][0]["distance"].is_null());  // never
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
    EXPECT_TRUE(u32["fight_distances"][0]["distance"].is_number());
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
    EXPECT_NE(t.find("fight 1cm"), std::string::npos) << t;
    EXPECT_NE(t.find("fight 1mm"), std::string::npos) << t;
    EXPECT_NE(t.find("d=10000"), std::string::npos) << t;
    // unorm16's row starts with its bits and its 65536 values, uint32_inv's range is d>=1 and its
    // d=0.1 cell is "-", linear_f32 never fights.
    EXPECT_NE(t.find("unorm16             16        65536  all"), std::string::npos) << t;
    EXPECT_NE(t.find("uint32_inv          32   4294537800  d>=1          -"), std::string::npos) << t;
    const size_t lin = t.find("linear_f32");
    ASSERT_NE(lin, std::string::npos);
    const std::string linRow = t.substr(lin, t.find('\n', lin) - lin);
    EXPECT_NE(linRow.find("never      never"), std::string::npos) << linRow;
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

}  // namespace
}  // namespace va
