// Per-view z-fighting analysis (docs/depth-formats.md, Audits: "Depth formats"; rules in docs/zfighting.md).
//
// For one view, from the screen triangles the z-buffer draws (the clip stage's output):
//   1. the two nearest surfaces at every pixel: the nearest and second-nearest fragments from
//      *distinct source triangles*, with their exact double view depths (findTwoNearest, over
//      render/raster_core.h's forEachFragment: the z-buffer's own coverage, fill rule and depth);
//   2. per depth format, whether the pixel *fights*: the two stored values are equal or in the
//      wrong order (ordering keys of render/depth_format.h: key(d1) >= key(d2) with d1 <= d2);
//   3. a geometric class for every fighting pixel: shared_edge (the two triangles share an edge
//      that passes near the pixel), intersection (the triangles' intersection line crosses the
//      pixel), coplanar (the triangles lie in one plane), separated (everything else);
//   4. hotspots: 8-connected components of the pixels that fight in at least one format and are
//      coplanar or separated (shared-edge and intersection pixels are no hotspots);
//   5. per format counts and the recommended format: the fewest bits that fights nowhere in this
//      view apart from coplanar surfaces (no format can order those);
//   6. per listed hotspot, why it fights: its depth gap, the view format's stored-value bucket width
//      at its depth, and the cheapest format whose bucket there is no wider than the gap.
//
// Usage (one call per view, after the clip stage):
//     ZFightResult z = analyzeZFighting(scene, cam, clip.out, ZFightSettings{});
//     if (!z.error.empty()) { ... bad settings ... }
//     writeZFightImage(z, view.buffer, dir + "/NAME.zfight.png", &err);   // reports/zfight_image.h
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"
#include "render/depth_format.h"
#include "render/raster.h"

namespace va {

// ---- Pass 1: the two nearest surfaces per pixel -----------------------------------------------

constexpr uint32_t kNoFragment = 0xFFFFFFFFu;

// Per pixel (row-major, (0,0) top-left), the nearest and second-nearest *surfaces*: a surface is a
// source triangle, so the clipped pieces of one source triangle are one surface (they share one
// depth plane and, by the fill rule, never cover the same pixel center twice; if they ever did,
// the nearer depth is kept). "Nearest" orders by exact double view depth; equal depths keep the
// first drawn (submission order) as the nearer one, as the z-buffer's LESS test does.
struct TwoNearest {
    int width = 0, height = 0;
    std::vector<double> depth1, depth2;     // exact view depth (double); +inf = no such surface
    std::vector<uint32_t> screen1, screen2; // index into ScreenTriangles (the first piece of the
                                            // surface that produced the kept depth); kNoFragment = none
    size_t pixels() const { return depth1.size(); }
};
// singleSided: as ZBufferSettings::singleSided (null: every triangle is drawn).
TwoNearest findTwoNearest(const ScreenTriangles &tris, int width, int height, bool orthographic,
                          const uint8_t *singleSided = nullptr);
// The same into `out`, its storage reused.
void findTwoNearest(const ScreenTriangles &tris, int width, int height, bool orthographic, const uint8_t *singleSided,
                    TwoNearest &out);

struct ReferenceVisibility;
// The same result, reading the fragments the reference visibility recorded for this view
// (audit.h: its fragment cache, complete) instead of walking them again: a screen triangle of
// `tris` takes its fragments from the reference's screen triangle of the same source and piece when
// the two have the same corners and depth plane and the reference's walk drew it (its single-sided
// rule, singleSidedTriangles of `scene`): forEachFragment gives both the same fragments. The others
// are walked here. Fragments are applied band by band (the per-pixel state of 16 rows stays in the
// core's cache), in each band by triangle in submission order, so each pixel sees its fragments in
// the walk's order; bandDone(p0, p1), when given, is called once pixels [p0, p1) are final (while
// they are still in the cache). Returns false (out untouched) when the reference has no complete
// cache.
bool findTwoNearestFromReference(const Scene &scene, const ReferenceVisibility &ref, const ScreenTriangles &tris,
                                 int width, int height, bool orthographic, const uint8_t *singleSided, TwoNearest &out,
                                 const std::function<void(size_t, size_t)> &bandDone = {});

// ---- Pixels that cannot fight, decided without encoding (zfight.cpp, 2a) ----------------------

// The relative window beyond which a format's computed key keeps the order of the depths inside
// [minValidDepth, far]: for d < d' with d' >= d (1 + window), key(d) <= key(d'). 0: exactly
// monotone; negative: no such window is claimed (the format is not filtered). Derived per format
// in zfight.cpp.
double monotoneWindow(const DepthEncoder &e);

// Cells over a depth range [dMin, dMax] (the camera's [near, far] in the audit; equal steps of the
// doubles' bit patterns, at most 4096, 256 or more per octave below a 2^16 ratio) with, per format, the first cell from which a farther depth's key
// is certainly above a nearer depth's: a pair of depths d1 <= d2 in cells c1, c2 with
// cannotFight(format, c1, c2) has key(d1) < key(d2) and both depths in the format's range, so it
// neither fights nor is out of range there -- without encoding either depth.
struct FightFilter {
    FightFilter(const std::vector<DepthEncoder> &encoders, double dMin, double dMax);
    uint32_t cell(double d) const;  // `count` for depths outside the cells (never decided)
    bool filtered(size_t format) const { return windows[format] >= 0 && count > 0; }
    bool filteredAll() const {
        for (size_t i = 0; i < windows.size(); ++i)
            if (!filtered(i)) return false;
        return true;
    }
    bool cannotFight(size_t format, uint32_t c1, uint32_t c2) const {
        const Cells &c = perFormat[format];
        return filtered(format) && c.firstSafe[c1] <= c2 && c2 <= c.last;
    }
    // In every filtered format at once (false when no format is filtered).
    bool cannotFightAny(uint32_t c1, uint32_t c2) const {
        return anyFiltered && firstSafeAll[c1] <= c2 && c2 <= lastAll;
    }

    struct Cells {
        std::vector<uint32_t> firstSafe;  // per cell + "outside": the first safe c2, count + 1 for none
        uint32_t last = 0;                // the last cell inside the format's range
    };
    uint64_t base = 0;
    int shift = 0;
    uint32_t count = 0;
    std::vector<double> windows;
    std::vector<Cells> perFormat;
    std::vector<uint32_t> firstSafeAll;
    uint32_t lastAll = 0;
    bool anyFiltered = false;
};

// ---- Classes of a pixel with two surfaces -----------------------------------------------------

enum class ZPixelClass : uint8_t {
    none = 0,      // fewer than two surfaces, or fights in no format (not classified)
    separated,     // two surfaces that are neither of the below: a genuine fight (hotspot material)
    coplanar,      // the two source triangles lie in one plane (up to the coordinates' precision):
                   // no format can order them; a genuine fight, hotspot material
    shared_edge,   // the triangles share an edge (exactly two common vertex positions) and the
                   // pixel center is within ZFightSettings::sharedEdgePixels of its projection
    intersection,  // the triangles' depth planes cross inside the pixel's square (interpenetration
                   // or contact line): the fight is the intersection line itself, not a hotspot
};
const char *zPixelClassName(ZPixelClass c);

// ---- Settings and result ----------------------------------------------------------------------

struct ZFightSettings {
    // Evaluated formats, in tie-break order: by default docs/depth-formats.md's classic twelve
    // (defaultZFightFormats); the others (and log24:C=X) are opt-in.
    std::vector<DepthFormatSpec> formats{defaultZFightFormats().begin(), defaultZFightFormats().end()};
    // The view's own format (the pipeline sets it): each hotspot gives its bucket width. Unset: the
    // hotspots leave that out.
    std::optional<DepthFormatSpec> viewFormat;
    uint64_t minHotspotArea = 1;    // components with fewer pixels are not hotspots (their pixels
                                    // still count as fighting pixels)
    size_t maxHotspotsListed = 50;  // hotspots kept with details (largest first); all are counted
    double sharedEdgePixels = 1.0;  // shared_edge radius: pixel center to projected edge, in pixels
    // As ZBufferSettings::singleSided: per source triangle, nonzero = drawn only with the front
    // winding on screen. Pass the pointer the view's z-buffer gets (null: every triangle counts).
    const uint8_t *singleSided = nullptr;
    // The view's reference visibility, when the audit ran and still holds its fragment cache: the
    // two nearest surfaces are read from it (findTwoNearestFromReference; the same result).
    const ReferenceVisibility *reference = nullptr;
};

struct ZFightFormatStats {
    DepthFormatSpec format;
    std::string name;         // depthFormatName(format)
    int bits = 0;
    // Pixels whose two surfaces fight in this format and are hotspot material (separated or
    // coplanar). Best 0.
    uint64_t fightingPixels = 0;
    uint64_t coplanarPixels = 0;      // of fightingPixels: coplanar surfaces (no format helps)
    uint64_t sharedEdgePixels = 0;    // fighting pixels classified shared_edge (not hotspots)
    uint64_t intersectionPixels = 0;  // fighting pixels classified intersection (not hotspots)
    uint64_t hotspots = 0;            // hotspots with at least one pixel fighting in this format. Best 0
    // Covered pixels where the nearest surface, or the second one when there is one, lies outside
    // what the format represents (the encoder clamps it). Best 0.
    uint64_t outOfRangePixels = 0;
};

struct ZFightHotspotFormat {
    DepthFormatSpec format;
    uint64_t pixels = 0;  // hotspot pixels that fight in this format (> 0)
};

struct ZFightHotspot {
    uint32_t id = 0;          // 1-based rank: area descending, ties by first pixel in scan order
    uint64_t area = 0;        // pixels
    int minX = 0, minY = 0, maxX = 0, maxY = 0;  // pixel bounding box, inclusive
    Vec3 centroid;            // world space: mean of the nearest surface's points at the pixel centers
    double depth = 0;         // median view depth of the nearest surface (m)
    double depthGap = 0;      // median of |d2 - d1| over its pixels (view depth, world units); 0 when coplanar
    double depthGapMax = 0;   // largest |d2 - d1|
    uint64_t coplanarPixels = 0;   // pixels whose surfaces are coplanar (== area: a coplanar hotspot)
    // The pair of source triangles fighting at most of its pixels (ties: smallest ids), lower id
    // first, with their source objects' names; pairPixels counts the pixels of that pair.
    uint32_t triangleA = 0, triangleB = 0;
    std::string objectA, objectB;
    uint64_t pairPixels = 0;
    uint64_t pairs = 0;       // distinct triangle pairs in the hotspot
    std::vector<ZFightHotspotFormat> formats;  // formats fighting at its pixels, in settings order
    // Why it fights, at `depth` with the gap `depthGap` (docs/zfighting.md, "Why a hotspot fights"):
    //   viewBucketWidth: the width (m) of the view format's stored-value bucket at `depth` (the
    //     interval of depths storing the same value, analysis/audits/depth_audit.h); wider than the gap:
    //     two surfaces the gap apart there can share a value. Absent without a view format or when
    //     `depth` lies outside its range. Best: below depthGap.
    //   cheapestFormat: the first format of depthFormatsCheapestFirst() (fewest bits, then the
    //     least change to a renderer) whose bucket at `depth` is no wider than depthGap, so no two
    //     surfaces depthGap apart at that depth share its value; cheapestBucketWidth is that width.
    //     Absent when no format is: coplanar surfaces (gap 0: coplanar set), or a gap below every
    //     format's bucket there.
    std::optional<double> viewBucketWidth;
    std::optional<DepthFormat> cheapestFormat;
    std::optional<double> cheapestBucketWidth;
    bool coplanar = false;    // coplanarPixels == area, or a median gap of 0: no format can help
    std::string why;          // the above in one sentence
};

struct ZFightResult {
    std::string error;        // empty = ok; else what is wrong with the settings and the fix
    int width = 0, height = 0;
    double nearZ = 0, farZ = 0;
    std::vector<DepthFormatSpec> formats;   // as evaluated (settings order)
    uint64_t coveredPixels = 0;             // pixels with at least one surface
    uint64_t twoSurfacePixels = 0;          // pixels with two surfaces (from distinct triangles)
    uint64_t fightingPixelsAnyFormat = 0;   // pixels fighting in at least one format (any class)
    // Pixels fighting in at least one format, by class (sum = fightingPixelsAnyFormat).
    uint64_t separatedPixels = 0, coplanarPixels = 0, sharedEdgePixels = 0, intersectionPixels = 0;
    std::vector<ZFightFormatStats> perFormat;  // one per format, settings order
    uint64_t hotspotCount = 0;                  // all hotspots (area >= minHotspotArea). Best 0
    std::vector<ZFightHotspot> hotspots;        // the first maxHotspotsListed of them, by id

    // The format with the fewest bits whose fightingPixels - coplanarPixels is 0 (ties: settings
    // order, which is docs/depth-formats.md's table order by default). Absent when every format fights at
    // non-coplanar surfaces. recommendation says why, in one sentence, and names coplanar pixels
    // when there are any ("coplanar surfaces fight in every format: offset the decal or use a
    // depth bias").
    std::optional<DepthFormatSpec> recommended;
    std::string recommendation;

    // Per-pixel layers for the image (pixel = y * width + x): the class of every pixel; the few
    // pixels that fight somewhere (about 1% of a view or fewer) and those of hotspots as lists,
    // ascending in pixel (a whole-view array of each cost more to clear than the analysis).
    std::vector<uint8_t> pixelClass;     // ZPixelClass
    std::vector<uint32_t> fightPixels;   // the pixels fighting in some format
    std::vector<uint32_t> fightMasks;    // per fightPixels entry: bit i = fights in formats[i] (nonzero)
    std::vector<uint32_t> hotspotPixels; // the pixels of hotspots (every component, listed or not)
    std::vector<uint32_t> hotspotIds;    // per hotspotPixels entry: its hotspot id (1-based)
    double ms = 0;                       // wall time of the analysis (the pipeline's clock)
    // Pixel p's fight mask (0: fights nowhere) and hotspot id (0: none).
    uint32_t fightMaskAt(size_t p) const { return valueAt(fightPixels, fightMasks, p); }
    uint32_t hotspotAt(size_t p) const { return valueAt(hotspotPixels, hotspotIds, p); }
    // Frees the per-pixel buffers once the images are written (the statistics and hotspots stay).
    void releasePixels() {
        std::vector<uint8_t>().swap(pixelClass);
        std::vector<uint32_t>().swap(fightPixels);
        std::vector<uint32_t>().swap(fightMasks);
        std::vector<uint32_t>().swap(hotspotPixels);
        std::vector<uint32_t>().swap(hotspotIds);
    }

private:
    static uint32_t valueAt(const std::vector<uint32_t> &pixels, const std::vector<uint32_t> &values, size_t p) {
        const auto it = std::lower_bound(pixels.begin(), pixels.end(), p, [](uint32_t a, size_t b) { return a < b; });
        return it != pixels.end() && *it == p ? values[size_t(it - pixels.begin())] : 0;
    }
};

// The analysis. `tris` are the triangles the z-buffer draws for this view (clip stage output);
// their `source` indices are scene triangle ids (names and vertex positions come from `scene`).
// Invalid settings (no formats, a repeated format, more than 32 formats, a format that cannot
// encode the camera's range (validateDepthFormatRange), sharedEdgePixels not finite or < 0) return
// a result with `error` set.
ZFightResult analyzeZFighting(const Scene &scene, const Camera &cam, const ScreenTriangles &tris,
                              const ZFightSettings &settings = {});

// The per-format stats of `format` in r, or nullptr when it was not evaluated.
const ZFightFormatStats *zfightStatsOf(const ZFightResult &r, const DepthFormatSpec &format);

// Why surfaces `gap` apart at view depth `depth` fight (or not), for a view with near/far and its
// format (optional): fills the hotspot's viewBucketWidth, cheapestFormat, cheapestBucketWidth and
// why. `coplanar`: the surfaces lie in one plane (no format can order them).
void explainHotspot(double nearZ, double farZ, const std::optional<DepthFormatSpec> &viewFormat, bool coplanar,
                    ZFightHotspot *h);

}  // namespace va
