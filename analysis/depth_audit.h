// View-independent depth-format audit (DESIGN.md, Audits: "Depth formats"; docs/depth-formats.md).
//
// For a near/far pair and a list of formats, measures from each format's own arithmetic
// (render/depth_format.h: depthKey / depthStoredValue, exactly what the z-buffer stores):
//   - the world-space depth resolution at the decade distances near, 10^k (near < 10^k < far), far,
//     next to the closed form (derivative of the mapping times the stored value's spacing);
//   - a dense resolution curve (for the log-log plot, reports/depth_plot.h);
//   - the number of distinct stored values over [near, far];
//   - the "fight distance": the smallest depth at which two surfaces a given gap apart (1 cm, 1 mm)
//     collapse to the same stored value (or swap order);
//   - the part of [near, far] the format can represent at all.
//
// Usage (the `visaudit depth-audit` command):
//     std::string err;
//     if (!validateDepthAuditRange(n, f, &err)) { print err; exit 2; }
//     DepthAuditResult r = auditDepthFormats(n, f, allDepthFormats());
//     if (!r.error.empty()) { print r.error; exit 2; }
//     depthAuditTable(r); depthAuditJson(r); writeDepthResolutionPlot(r, path, &err);
//
// Units: world units, meters by convention (1 cm = 0.01). Depth d is view depth (> 0).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "render/depth_format.h"

namespace va {

// ---- Per-format exact arithmetic the audit builds on ------------------------------------------

// The exact inverse of a format's mapping: the representative view depth of stored value `stored`
// (a value the format can hold, as depthStoredValue returns it). For rounding formats (unorm*,
// log24, every float format) it is the depth whose exact real-number image is `stored` itself (the
// center of the stored value's rounding interval); for truncating formats (int31_inv, uint32_inv,
// uint32_inv1) it is the depth whose image is stored + 0.5 (the center of [v, v + 1)). The
// formulas are in docs/depth-formats.md. Round trip: depthStoredValue(e, depthFromStored(e, v)) == v
// for every stored value a double depth produces (tests/test_depth_audit.cpp checks it); values
// no double depth reaches (floats just above 0 in f32) have an inverse but no round trip.
double depthFromStored(const DepthEncoder &e, double stored);

// depthFromStored(e, b) - depthFromStored(e, a), computed without cancellation (the difference
// of the two inverses written over a common denominator), so a step of 1e-12 m at 1e4 m is exact
// to a few ulps rather than lost in the subtraction of two nearly equal depths.
double depthBetweenStored(const DepthEncoder &e, double a, double b);

// The stored value of an ordering key (inverse of depthKeyFromStored).
double storedFromKey(const DepthEncoder &e, uint32_t key);

// True when surfaces at depths d and d + gap (gap > 0) are no longer ordered by the format: the
// farther one's key is not larger (equal stored values, or swapped). This is the z-fighting
// predicate the fight distance searches for.
bool depthFormatFights(const DepthEncoder &e, double d, double gap);

// ---- Result ------------------------------------------------------------------------------------

// Resolution of one format at one depth. Steps are world-space depth distances (meters, > 0);
// "absent" (std::nullopt, JSON null) where the step does not exist. Best values: small.
struct DepthResolutionSample {
    double depth = 0;            // d, the view depth sampled
    bool inRange = true;         // false: d is outside what the format can represent (int31_inv and
                                 // uint32_inv below d = 1); the steps below are then absent
    double stored = 0;           // the stored value at d (as depthStoredValue: float or integer)
    uint32_t key = 0;            // its ordering key (smaller = nearer)
    // Distance from d's stored value to the next distinct stored value towards far, both taken at
    // their representative depths (depthFromStored): depthFromStored(next) - depthFromStored(v).
    // "Next" is the stored value of the first double depth beyond d's bucket (found by bisecting
    // the encoder), so it is a value the format really produces. Absent at the format's last value
    // (d = far in formats that clamp at far).
    std::optional<double> stepToNext;
    // The same towards near: depthFromStored(v) - depthFromStored(previous). Absent at the first.
    std::optional<double> stepToPrev;
    // The resolution reported: stepToNext, or stepToPrev where there is no next value. Best: small.
    std::optional<double> resolution;
    // True when the neighbor behind `resolution` is more than one key away: the format holds values
    // in between that no double depth produces (f32 just above z = 0 at near, f32_reversed just
    // above 0 at far: floats there are denser than the doubles d), so the step is the input's
    // double spacing, not the format's. closedForm (the format's own spacing) is then far smaller.
    bool skipsValues = false;
    // Width of the interval of double depths that store exactly d's value, measured by bisecting
    // the encoder for both ends (the clamped first/last buckets are cut at near/far, so at near and
    // far of clamping formats this is about half the step). A cross-check of `resolution`.
    std::optional<double> bucketWidth;
    // The closed-form resolution: |d depth / d stored| at d times the stored spacing there (1 for
    // integers, the float's ulp for floats); docs/depth-formats.md lists it per format.
    std::optional<double> closedForm;
    // resolution / closedForm - 1: how far the linearized closed form is from the measured step
    // (0 is perfect agreement; float formats differ by up to -0.5 at powers of two, where the
    // spacing towards far halves).
    std::optional<double> relativeDifference;
};

// The fight distance for one gap.
struct DepthFightDistance {
    double gap = 0;                  // distance between the two surfaces (m), e.g. 0.01 or 0.001
    // The smallest depth d found at which surfaces at d and d + gap fight (depthFormatFights);
    // absent ("never") when they do not fight anywhere in the representable part of
    // [near, far - gap]. Best: absent, or large.
    std::optional<double> distance;
};

struct DepthFormatAudit {
    DepthFormat format = DepthFormat::f32;
    std::string name;                // format name as DESIGN.md and --formats spell it
    int bits = 0;                    // bits of the stored value
    bool nearerIsLarger = false;     // comparison direction of the stored value
    // Distinct stored values over [near, far] (exact, from the ordering keys: key(far) - key(near)
    // + 1; for floats that is the count of representable floats between the two stored values,
    // inclusive; a format clamping below near's depth counts from its clamp). Best: large.
    uint64_t distinctValues = 0;
    // The part of [near, far] the format represents: [representableNear, representableFar].
    // Depths outside it are clamped to the stored value at its end (and fight each other).
    double representableNear = 0;
    double representableFar = 0;
    std::string rangeNote;           // empty, or why part of [near, far] is not representable
    std::vector<DepthResolutionSample> decades;  // at DepthAuditResult::decadeDepths
    std::vector<DepthFightDistance> fights;      // one per DepthAuditResult::fightGaps
    // Dense curve for the plot: resolution at DepthAuditResult::curveDepths (absent where out of range).
    std::vector<std::optional<double>> curveResolution;
};

struct DepthAuditSettings {
    std::vector<double> fightGaps = {0.01, 0.001};  // surface gaps (m) for fight distances
    int curveSamples = 200;                         // dense-curve samples between near and far
    int fightScanSamples = 2000;                    // coarse log-spaced scan before bisection
};

struct DepthAuditResult {
    std::string error;               // empty = ok; otherwise what is wrong with the input and the fix
    double nearZ = 0, farZ = 0;      // the audited depth range [near, far]
    std::vector<double> decadeDepths;  // near, every 10^k strictly between, far
    std::vector<double> fightGaps;     // as DepthAuditSettings::fightGaps
    // Dense curve depths: geometric centers of curveSamples equal log-width bins over [near, far]
    // (strictly inside, so the singular end buckets of the clamping formats do not dominate).
    std::vector<double> curveDepths;
    std::vector<DepthFormatAudit> formats;  // in the order asked for
};

// Checks near/far: finite, 0 < near < far, far <= FLT_MAX (float formats must hold far).
// On failure returns false and *err names the value and the fix.
bool validateDepthAuditRange(double nearZ, double farZ, std::string *err);

// The audit. Invalid input (see validateDepthAuditRange; also an empty or repeated format list,
// a gap that is not finite and > 0) returns a result with `error` set and no formats.
DepthAuditResult auditDepthFormats(double nearZ, double farZ, const std::vector<DepthFormat> &formats,
                                   const DepthAuditSettings &settings = {});

}  // namespace va
