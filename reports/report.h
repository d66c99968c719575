// Report outputs: report.json (docs/report-schema.json) and the per-view images.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/limits.h"
#include "analysis/results.h"

namespace va {

constexpr const char *kReportFormat = "visaudit-report/1";

// The whole report as JSON (ordered keys, deterministic: no timestamps outside "ms" fields).
// Doubles are always finite: a value that is not (an empty scene's bounds, a ratio over zero
// pixels) is written as null; docs/report-schema.json says which fields can be null.
// Which images a run writes (--images): every one; the key ones (the page's first four per view:
// depth, overdraw, z-fighting, culling fates, as PNGs); none (CI runs that need only the numbers).
enum class ImageSet { all, key, none };
// Whether the image under report key `key` (depth_png, ids_exr, ...) is written in `set`: the one
// rule writeViewImages and reportJson's image lists follow.
inline bool imageWritten(ImageSet set, std::string_view key) {
    if (set == ImageSet::all) return true;
    if (set == ImageSet::none) return false;
    return key == "depth_png" || key == "overdraw_png" || key == "zfight_png" || key == "culling_png";
}

// `images`: the images the run wrote; each view's "images" lists only those.
nlohmann::ordered_json reportJson(const AnalysisResult &result, ImageSet images = ImageSet::all);
// The report's "totals" computed from its "views" array alone (reportJson and merge share it).
nlohmann::ordered_json reportTotals(const nlohmann::ordered_json &views);

// The output phase's timings in milliseconds (report.json's "output"): writing the files takes as
// long as the analysis itself at full HD, so it is timed like a stage, not hidden in the wall time.
struct OutputTimings {
    double imagesMs = 0;  // every view's images: pixels colored, encoded, written (sum over views)
    double reportMs = 0;  // the report built in memory (reportJson)
    double htmlMs = 0;    // report.html rendered and written
};
// Appends "output" to a report made by reportJson. Serializing and writing report.json itself
// comes after, so it is the one part of the output phase that the report cannot time.
void addOutputTimings(nlohmann::ordered_json *report, const OutputTimings &t);

// ---- Image file names ------------------------------------------------------------------------
// A view name made safe as a file name: [A-Za-z0-9._-] kept, every other byte replaced by '_'
// (a multi-byte UTF-8 character becomes one '_' per byte), a leading '.' replaced by '_' (no
// hidden files, no "." or ".."), empty -> "view", cut to kMaxImageBaseName bytes.
constexpr size_t kMaxImageBaseName = 200;
std::string sanitizeFileName(const std::string &viewName);
// The image base names of all views, in view order: sanitizeFileName of each, with collisions
// (compared case-insensitively, so they stay distinct on macOS/Windows file systems) resolved in
// view order by appending "-2", "-3", ...: the first view keeps the plain name. Deterministic.
std::vector<std::string> imageBaseNames(const std::vector<ViewResult> &views);
// The same names from the view specs, before the analysis (views[i] gets element i): a caller
// that writes each view's images as soon as it is analysed passes element i to writeViewImages.
std::vector<std::string> imageBaseNames(const std::vector<ViewSpec> &views);

// The image files of one view, named from its base name (the keys are report.json's "images").
struct ViewImageNames {
    std::string depthExr;     // BASE.depth.exr
    std::string depthPng;     // BASE.depth.png
    std::string overdrawPng;  // BASE.overdraw.png
    std::string idsExr;       // BASE.ids.exr
    std::string zfightPng;    // BASE.zfight.png (when the z-fighting analysis ran)
    std::string cullingPng;   // BASE.culling.png (when the audit ran)
    std::string raycastIdsExr;   // BASE.raycast.ids.exr (when the raycast stage ran)
    std::string raycastDiffPng;  // BASE.raycast_diff.png
    std::string secondaryPng;    // BASE.secondary.png (when secondary rays ran)
    std::string base;            // BASE itself
};
ViewImageNames viewImageNames(const std::string &baseName);
// BASE.shadow.LIGHT.png for light l of the view's effects (the light's name sanitized; its index
// when the sanitized name is empty or repeats).
std::string shadowImageName(const ViewImageNames &names, size_t light, const ViewResult &view);

// ---- Images ------------------------------------------------------------------------------------
// Writes BASE.depth.exr, BASE.depth.png, BASE.overdraw.png and BASE.ids.exr for one view into dir
// (writeFileAtomic: in place inside a report's staging folder, elsewhere a temporary name renamed).
// Needs view.buffer (width x height). On failure returns false with the path and the reason.
bool writeViewImages(const ViewResult &view, const std::string &dir, const std::string &baseName,
                     std::string *err, ImageSet set = ImageSet::all);
// As above with baseName = sanitizeFileName(view name): for a single view only; use
// writeAllViewImages (or imageBaseNames) when view names may collide.
bool writeViewImages(const ViewResult &view, const std::string &dir, std::string *err);
// Every view's images with the names imageBaseNames gives (the names report.json lists).
bool writeAllViewImages(const AnalysisResult &result, const std::string &dir, std::string *err);

// An image read back as stored (for tests, golden-image comparison, level maps and grading): a PNG
// (8- or 16-bit; a palette as RGB) or an OpenEXR file (every channel in the first one's type; R, G,
// B, A first), told apart by their signatures (reports/image_read.cpp). Exactly one pixel vector
// is filled, the one matching the pixel type; channels are interleaved, rows top-down.
struct ImageData {
    int width = 0, height = 0;
    std::vector<std::string> channelNames;
    std::string pixelType;       // "float", "uint" (32-bit), "uint8", "uint16" (OpenImageIO's names)
    std::vector<float> f32;      // pixelType "float"
    std::vector<uint32_t> u32;   // pixelType "uint"
    std::vector<uint8_t> u8;     // pixelType "uint8"
    std::vector<uint16_t> u16;   // pixelType "uint16"
    int channels() const { return int(channelNames.size()); }
};
bool readImage(const std::string &path, ImageData *out, std::string *err);

// The overdraw heatmap's color for a depth complexity (fragments at a pixel) on a scale capped at
// `cap` (values above it take the top color): 0 = black, 1 = the ramp's start (blue), cap = white.
struct Rgb8 {
    uint8_t r = 0, g = 0, b = 0;
    bool operator==(const Rgb8 &) const = default;
};
Rgb8 overdrawColor(uint32_t fragments, uint32_t cap);
// The 8-bit gray of a view depth in the depth PNG (log scale between the view's minimum and
// maximum finite depth): dMin -> 255 (white), dMax -> kDepthPngFarGray, background -> 0.
constexpr uint8_t kDepthPngFarGray = 40;
uint8_t depthGray(double d, double dMin, double dMax);
// depthGray for one view's range, with the range's logarithms taken once rather than per pixel
// (the same operations on the same values, so the same grays): what an image's loop uses.
struct DepthGrayScale {
    bool valid, spread;
    double logMin = 0, logSpan = 0;
    DepthGrayScale(double dMin, double dMax) : valid(dMin > 0 && std::isfinite(dMax)), spread(dMax > dMin) {
        if (valid && spread) {
            logMin = std::log(dMin);
            logSpan = std::log(dMax) - logMin;
        }
    }
    uint8_t operator()(double d) const {
        if (!std::isfinite(d) || !(d > 0) || !valid) return 0;
        double t = 0;
        if (spread) t = (std::log(d) - logMin) / logSpan;
        t = std::clamp(t, 0.0, 1.0);
        // lround(x) for x in [kDepthPngFarGray, 255]: x + 0.5 is exact there, or rounds only where
        // it reaches a new power of two (64, 128, 256), whose floor is then already x's rounding.
        return uint8_t(255.0 - t * (255.0 - kDepthPngFarGray) + 0.5);
    }
};
// The nearest and farthest finite positive depth of a view (depthGray's range): +inf / -inf when
// nothing is drawn.
void depthRange(const std::vector<double> &depth, double *dMin, double *dMax);
// The gray scale of a view's depths over their own range (depthRange): what each image draws its
// gray background with.
inline DepthGrayScale depthGrayScale(const std::vector<double> &depth) {
    double lo, hi;
    depthRange(depth, &lo, &hi);
    return DepthGrayScale(lo, hi);
}

// A depth buffer's gray per pixel (depthGrayScale over its own range): computed once per view and
// shared by every image drawn over that buffer (a logarithm per pixel, not one per pixel and image).
// The grays' range (depthRange) is stored where asked.
std::vector<uint8_t> depthGrays(const std::vector<double> &depth, double *dMin = nullptr, double *dMax = nullptr);
// The same grays, from those of another buffer that mostly holds the same depths (knownGrays =
// depthGrays(known, &knownMin, &knownMax); a view's reference and z-buffer depths differ at a few
// pixels): where both buffers have the same range, a pixel with the same depth (bit for bit) has
// the same gray, and only the others are computed. Another range, or another size: depthGrays.
std::vector<uint8_t> depthGraysFrom(const std::vector<double> &depth, const std::vector<double> &known,
                                    const std::vector<uint8_t> &knownGrays, double knownMin, double knownMax);
// An image writer's grays by pixel: the caller's shared ones (depthGrays of the same buffer) when
// given, else computed here; the same bytes either way.
class PixelGrays {
  public:
    PixelGrays(const std::vector<double> &depth, const std::vector<uint8_t> *shared)
        : depth_(depth), shared_(shared && shared->size() == depth.size() ? shared->data() : nullptr),
          scale_(shared_ ? DepthGrayScale(0, 0) : depthGrayScale(depth)) {}
    uint8_t operator[](size_t i) const { return shared_ ? shared_[i] : scale_(depth_[i]); }

  private:
    const std::vector<double> &depth_;
    const uint8_t *shared_;
    DepthGrayScale scale_;
};

// ---- Files and folders -----------------------------------------------------------------------
// Reads and parses a JSON file (a report, a baseline, a submission). `unreadable`: the file cannot
// be opened or read; `invalid`: not JSON, *detail gets the parser's message. Callers word the error.
// `tooDeep`: nested deeper than maxDepth (json::checkDepth), *detail gets the whole message.
enum class JsonRead { ok, unreadable, invalid, tooDeep };
JsonRead readJsonDocument(const std::string &path, nlohmann::ordered_json *out, std::string *detail,
                          uint64_t maxDepth = kDefaultMaxJsonDepth);

// Writes a file atomically: a temporary name in the same folder, flushed (fsync), then renamed. A
// file directly inside an open OutputDir's staging folder is written plainly instead: the folder
// is invisible until OutputDir::commit, which flushes it as a whole before the swap, so a temporary
// name and a flush per file (one journal commit each: 5 ms per image here) buy nothing there.
bool writeFileAtomic(const std::string &path, const std::string &contents, std::string *err);
// Images written the same way, for the other image writers of reports/: an interleaved RGB8 PNG
// (libpng; stored with a palette when it has at most 256 colors, as every visualization here does:
// the same pixels read back, a third of the bytes to compress), and a one-channel UINT32 EXR (ids,
// OpenEXRCore). `chunks`, when given, carries an EXR's compressed chunks from one write to the next:
// a chunk whose rows are byte-identical to the same chunk of the image written before (same size
// and type; its pixels must still be alive) is not compressed again (the z-buffer's and the ray
// caster's ids agree on about half of them), and afterwards it holds this image's.
struct ExrChunks {
    const void *pixels = nullptr;  // the image they were written from
    int width = 0, height = 0;
    bool isFloat = false;
    std::vector<std::vector<uint8_t>> bytes;  // per chunk: its compressed bytes; empty: stored as it is
};
bool writePngRgb8(const std::string &path, int width, int height, const uint8_t *rgb, std::string *err);
bool writeExrUint32(const std::string &path, int width, int height, const uint32_t *values, const char *channel,
                    std::string *err, ExrChunks *chunks = nullptr);

// An output directory written as a whole or not at all: files go into a staging folder next to
// the target, and commit() swaps it in. An existing target is replaced only if it is a visaudit
// folder (holds report.json, pvs-audit.json, an assignment kit's assignment.json or answers.json, a
// grade's grade.json or grades.csv) or empty; anything else is refused, never deleted.
class OutputDir {
  public:
    OutputDir() = default;
    OutputDir(const OutputDir &) = delete;
    OutputDir &operator=(const OutputDir &) = delete;

    bool open(const std::string &target, std::string *err);
    const std::string &staging() const { return staging_; }
    const std::string &target() const { return target_; }
    // Flushes the staging folder's files to disk (syncfs: one flush for all of them), then swaps
    // it in. Returns false (old target restored) when the flush or the swap fails. When
    // the swap succeeded but the replaced old folder could not be removed, returns true and *err
    // holds a warning naming the leftover folder.
    bool commit(std::string *err);
    ~OutputDir();  // removes the staging folder unless committed

  private:
    std::string target_, staging_;
    bool committed_ = false;
};

}  // namespace va
