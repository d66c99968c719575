// Per-view images: PNGs through libpng (palette images, encodePng), EXRs through OpenEXRCore
// (writeExr); reading them is reports/image_read.cpp's.
//
//   BASE.depth.exr     one FLOAT channel "Z": the visible fragment's view depth d (double rounded to
//                      float); background (no fragment) = +inf, so "nothing" is never mistaken for a
//                      depth and min() over a region still picks the nearest surface.
//   BASE.depth.png     8-bit gray visualization of the same depths (depthGray: log scale, near
//                      white, far dark, background black).
//   BASE.overdraw.png  heatmap of depth complexity (ZBuffer::fragments per pixel) with a legend
//                      strip added below the image (the image itself is never covered).
//   BASE.ids.exr       one UINT32 channel "id": 1 + the visible source triangle index, 0 = background.
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <optional>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <OpenEXR/openexr.h>
#include <png.h>
#include <immintrin.h>
#include <libdeflate.h>
#include <zlib.h>

#include "common/uninit_vector.h"
#include "reports/font.h"
#include "reports/legend.h"
#include "reports/palette_image.h"
#include "reports/report.h"
#include "reports/audit_images.h"
#include "reports/effects_images.h"
#include "reports/ordering_images.h"
#include "reports/zfight_image.h"

namespace va {

namespace {

// ---- PNG ----------------------------------------------------------------------------------------
// Every PNG is a visualization with few colors (a view's grays and a handful of highlight colors):
// stored with a palette when it has at most 256, one byte per pixel instead of three, and the
// deflate pass that dominates writing a PNG runs over a third of the bytes. The pixels read back
// are the same either way. Measured per 1080p image (libpng 1.6, zlib 1.2.13, filter "up", zlib's
// run-length strategy -- most rows repeat the row above, so the filter turns them into zero runs
// and the run-length coder needs no match search): RGB 15 ms, palette 7 ms plus 1-4 ms to index it.

// The distinct colors of an RGB8 image in order of first appearance and each pixel's index into
// them; false when there are more than 256. A row equal to the one above copies its indices.
bool paletteOf(const uint8_t *rgb, int width, int height, std::vector<uint8_t> *index, std::vector<png_color> *colors) {
    const size_t W = size_t(width), row = 3 * W;
    index->resize(W * size_t(height));
    colors->clear();
    // Open addressing over the 24-bit colors, 1024 slots for at most 256 colors.
    constexpr uint32_t kSlots = 1024, kEmpty = 0xFFFFFFFFu;
    uint32_t key[kSlots];
    uint8_t value[kSlots];
    std::fill(std::begin(key), std::end(key), kEmpty);
    uint32_t last = kEmpty;
    uint8_t lastIndex = 0;
    for (size_t y = 0; y < size_t(height); ++y) {
        const uint8_t *p = rgb + y * row;
        uint8_t *out = index->data() + y * W;
        if (y > 0 && std::memcmp(p, p - row, row) == 0) {
            std::memcpy(out, out - W, W);
            continue;
        }
        for (size_t x = 0; x < W; ++x, p += 3) {
            const uint32_t k = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16;
            if (k != last) {
                uint32_t h = (k * 2654435761u) >> 22;
                while (key[h] != kEmpty && key[h] != k) h = (h + 1) & (kSlots - 1);
                if (key[h] == kEmpty) {
                    if (colors->size() == 256) return false;
                    key[h] = k;
                    value[h] = uint8_t(colors->size());
                    colors->push_back({p[0], p[1], p[2]});
                }
                last = k;
                lastIndex = value[h];
            }
            out[x] = lastIndex;
        }
    }
    return true;
}

void appendPngBytes(png_structp png, png_bytep data, png_size_t n) {
    static_cast<std::string *>(png_get_io_ptr(png))->append(reinterpret_cast<const char *>(data), n);
}
void flushNothing(png_structp) {}

// zlib's stream at level 1 with a 32 KB window built from its parts: the two header bytes
// deflateInit2 writes for it, raw deflate from a stream kept per thread (reset, not set up again,
// per call: the same bytes as compress2's or as a fresh stream's), and the Adler-32 trailer from
// libdeflate (SIMD: zlib 1.2's scalar one took a fifth of an EXR chunk's time). The strategy is
// zlib's (the EXR chunks use the default, PNGs libpng's run-length one). compress() returns the
// stream's size, or 0 when it does not fit in `out` or zlib fails.
class ZlibLevel1 {
  public:
    explicit ZlibLevel1(int strategy) { ok_ = deflateInit2(&z_, 1, Z_DEFLATED, -15, 8, strategy) == Z_OK; }
    ~ZlibLevel1() {
        if (ok_) deflateEnd(&z_);
    }
    ZlibLevel1(const ZlibLevel1 &) = delete;
    ZlibLevel1 &operator=(const ZlibLevel1 &) = delete;

    size_t compress(const uint8_t *in, size_t n, uint8_t *out, size_t capacity) {
        if (!ok_ || capacity < 6 || n > UINT32_MAX || deflateReset(&z_) != Z_OK) return 0;
        out[0] = 0x78;  // CMF: deflate, 32 KB window
        out[1] = 0x01;  // FLG: level 1's "fastest" level bits, FCHECK making the pair a multiple of 31
        z_.next_in = const_cast<uint8_t *>(in);
        z_.avail_in = uInt(n);
        z_.next_out = out + 2;
        z_.avail_out = uInt(std::min<size_t>(capacity - 6, UINT32_MAX));
        if (deflate(&z_, Z_FINISH) != Z_STREAM_END) return 0;
        const size_t size = 2 + size_t(z_.total_out);
        const uint32_t adler = libdeflate_adler32(1, in, n);
        for (int i = 0; i < 4; ++i) out[size + size_t(i)] = uint8_t(adler >> (24 - 8 * i));  // big-endian
        return size + 4;
    }

  private:
    z_stream z_{};
    bool ok_ = false;
};

// The image data of a PNG of more than kPngSmallImage filtered bytes written as libpng 1.6 would
// write it, at half its time: libpng filters, deflates and checksums row by row (filter, Adler-32
// and CRC each a scalar byte loop), while here the "up" filter runs over the whole image in
// vectorized loops, zlib deflates it in one call with the settings libpng gives it (level 1,
// run-length strategy, a 32 KB window -- libpng narrows the window only for images of at most
// kPngSmallImage bytes, which take libpng's own path), libdeflate adds the Adler-32, and the zlib
// stream goes out in IDAT chunks of libpng's 8 KB buffer, then IEND. The same bytes as libpng's
// rows: zlib's output does not depend on how its input is split, and the first row is filtered
// "up" from a row of zeros as libpng does (tested: ReportImages.PngDirectIdatEqualsLibpngRows).
constexpr size_t kPngSmallImage = 16384;
constexpr size_t kPngIdatChunk = 8192;  // libpng's PNG_ZBUF_SIZE

bool writeIdatDirect(png_structp png, int height, size_t rowBytes, const uint8_t *pixels, size_t stride) {
    thread_local std::vector<uint8_t> filtered, z;
    const size_t line = rowBytes + 1;
    if (size_t(height) * line > (size_t(1) << 31)) return false;  // zlib counts in 32 bits
    filtered.resize(size_t(height) * line);
    for (size_t y = 0; y < size_t(height); ++y) {
        uint8_t *__restrict d = filtered.data() + y * line;
        const uint8_t *__restrict c = pixels + y * stride;
        d[0] = height == 1 ? 0 : 2;  // libpng drops "up" for a one-row image
        if (y == 0) {
            std::memcpy(d + 1, c, rowBytes);
        } else {
            const uint8_t *__restrict u = c - stride;
            for (size_t x = 0; x < rowBytes; ++x) d[1 + x] = uint8_t(c[x] - u[x]);
        }
    }
    thread_local ZlibLevel1 zlib(Z_RLE);
    z.resize(compressBound(uLong(filtered.size())));
    const size_t size = zlib.compress(filtered.data(), filtered.size(), z.data(), z.size());
    if (size == 0) return false;
    static const png_byte idat[5] = "IDAT", iend[5] = "IEND";
    for (size_t at = 0; at < size; at += kPngIdatChunk)
        png_write_chunk(png, idat, z.data() + at, std::min(kPngIdatChunk, size - at));
    png_write_chunk(png, iend, nullptr, 0);
    return true;
}

// libpng reports errors by longjmp to the setjmp below; nothing between them owns a resource that
// the jump would leak (the rows are the caller's, the output string is the caller's).
bool encodePngRows(int width, int height, int colorType, const std::vector<png_color> &palette, const uint8_t *pixels,
                   size_t stride, std::string *out, std::string *why) {
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        *why = "libpng could not allocate its writer";
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        *why = "libpng failed to encode the image";
        return false;
    }
    png_set_write_fn(png, out, appendPngBytes, flushNothing);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_set_compression_strategy(png, Z_RLE);
    png_set_compression_level(png, 1);
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, colorType, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_PLTE(png, info, palette.data(), int(palette.size()));
    png_write_info(png, info);
    const size_t rowBytes = size_t(width) * (colorType == PNG_COLOR_TYPE_RGB ? 3 : 1);
    const size_t filteredSize = size_t(height) * (rowBytes + 1);
    if (filteredSize <= kPngSmallImage || !writeIdatDirect(png, height, rowBytes, pixels, stride)) {
        for (int y = 0; y < height; ++y) png_write_row(png, pixels + size_t(y) * stride);
        png_write_end(png, info);
    }
    png_destroy_write_struct(&png, &info);
    return true;
}

// An 8-bit PNG of 1 (gray) or 3 (RGB) channels: RGB with a palette when it has at most 256 colors.
bool encodePng(int width, int height, int channels, const uint8_t *pixels, std::string *out, std::string *why) {
    if (width <= 0 || height <= 0 || (channels != 1 && channels != 3)) {
        *why = "a PNG needs a positive size and 1 or 3 channels (got " + std::to_string(width) + "x" +
               std::to_string(height) + "x" + std::to_string(channels) + ")";
        return false;
    }
    out->clear();
    if (channels == 1) return encodePngRows(width, height, PNG_COLOR_TYPE_GRAY, {}, pixels, size_t(width), out, why);
    std::vector<uint8_t> index;
    std::vector<png_color> palette;
    if (paletteOf(pixels, width, height, &index, &palette))
        return encodePngRows(width, height, PNG_COLOR_TYPE_PALETTE, palette, index.data(), size_t(width), out, why);
    return encodePngRows(width, height, PNG_COLOR_TYPE_RGB, {}, pixels, 3 * size_t(width), out, why);
}

// From pixel i, whole groups of 16 codes equal to `c` written as its index `s`; returns the first
// pixel of the first group that is not (or of the last partial group).
__attribute__((target("avx2"))) size_t sameCodeRunAvx2(const uint16_t *code, size_t i, size_t n, uint16_t c, uint8_t s,
                                                       uint8_t *out) {
    const __m256i cc = _mm256_set1_epi16(int16_t(c));
    const __m128i ss = _mm_set1_epi8(char(s));
    for (; i + 16 <= n; i += 16) {
        const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(code + i));
        if (_mm256_movemask_epi8(_mm256_cmpeq_epi16(v, cc)) != -1) break;
        _mm_storeu_si128(reinterpret_cast<__m128i *>(out + i), ss);
    }
    return i;
}

// The codes of a PaletteImage as PNG palette indices, the palette in order of first appearance:
// the colors are distinct, so this is the palette paletteOf finds in the same pixels as RGB. False
// when more than 256 colors appear.
bool paletteIndices(const PaletteImage &img, std::vector<uint8_t> *index, std::vector<png_color> *colors) {
    // slot[code]: its palette index, or -1 until it appears; order[k]: the code of palette index k.
    // A new color is rare (a few hundred per image), so the loop is a table lookup per pixel.
    std::vector<int16_t> slot(img.colors.size(), -1);
    int16_t *__restrict sl = slot.data();
    uint16_t order[256];
    int count = 0;
    index->resize(img.code.size());
    const uint16_t *__restrict code = img.code.data();
    uint8_t *__restrict out = index->data();
    // A pixel with its left neighbour's code (most pixels: the pictures are flat areas and gray
    // ramps) starts a run checked 16 codes at a time.
    const bool avx2 = __builtin_cpu_supports("avx2");
    for (size_t i = 0, n = img.code.size(); i < n;) {
        const uint16_t c = code[i];
        int s = sl[c];
        if (s < 0) [[unlikely]] {
            if (count == 256) return false;
            order[count] = c;
            s = sl[c] = int16_t(count++);
        }
        out[i] = uint8_t(s);
        ++i;
        if (avx2 && i < n && code[i] == c) i = sameCodeRunAvx2(code, i, n, c, uint8_t(s), out);
    }
    colors->clear();
    for (int k = 0; k < count; ++k) colors->push_back({img.colors[order[k]].r, img.colors[order[k]].g, img.colors[order[k]].b});
    return true;
}

// Writes encoded bytes with writeFileAtomic (in place in a report's staging folder; elsewhere a
// temporary name, flushed, renamed over `path`: readers see the old file or the new one, never
// half). Its errors name the call and errno's text ("No space left on device").
bool writeEncoded(const std::string &path, const std::string &bytes, std::string *err) {
    std::string e;
    if (writeFileAtomic(path, bytes, &e)) return true;
    const std::string own = "cannot write '" + path + "': ";  // writeFileAtomic's prefix
    if (err) *err = "cannot write image '" + path + "': " + (e.rfind(own, 0) == 0 ? e.substr(own.size()) : e);
    return false;
}

bool writePng(const std::string &path, int width, int height, int channels, const uint8_t *pixels, std::string *err) {
    std::string bytes, why;
    if (!encodePng(width, height, channels, pixels, &bytes, &why)) {
        if (err) *err = "cannot write image '" + path + "': " + why;
        return false;
    }
    return writeEncoded(path, bytes, err);
}

// ---- OpenEXR --------------------------------------------------------------------------------------
// One-channel scanline images through OpenEXRCore (OpenEXR 3's C API) with ZIP compression, each
// chunk of 16 rows compressed here: OpenEXR's ZIP filter (the chunk's bytes split into the even and
// the odd ones, then each byte replaced by its difference to the previous + 128, modulo 256) as two
// loops the compiler vectorizes, then zlib at level 1. The same chunk bytes as OpenEXR's own
// compressor at level 1 (which OpenImageIO used until issue 18) at about 60% of the time: its
// filter loops byte by byte, and OpenImageIO converts scanline by scanline before it. A chunk that
// would not shrink is stored as it is (the format's rule; the reader knows it by its size). The
// header holds the required attributes only, so the file is the same in every run.
struct ExrSink {
    std::string bytes;
    std::string error;
};

int64_t exrWrite(exr_const_context_t, void *user, const void *buffer, uint64_t size, uint64_t offset,
                 exr_stream_error_func_ptr_t) {
    std::string &b = static_cast<ExrSink *>(user)->bytes;
    if (offset + size > b.size()) b.resize(offset + size);
    std::memcpy(b.data() + offset, buffer, size);
    return int64_t(size);
}


// The ZIP filter and zlib on `n` bytes; the compressed size, or 0 when zlib fails.
size_t zipChunk(const uint8_t *raw, size_t n, std::vector<uint8_t> &split, std::vector<uint8_t> &filtered,
                std::vector<uint8_t> &out) {
    split.resize(n);
    filtered.resize(n);
    const size_t half = (n + 1) / 2;
    uint8_t *__restrict even = split.data();
    uint8_t *__restrict odd = split.data() + half;
    for (size_t i = 0; i < n / 2; ++i) {
        even[i] = raw[2 * i];
        odd[i] = raw[2 * i + 1];
    }
    if (n & 1) even[n / 2] = raw[n - 1];
    const uint8_t *__restrict t = split.data();
    uint8_t *__restrict d = filtered.data();
    if (n) d[0] = t[0];
    for (size_t i = 1; i < n; ++i) d[i] = uint8_t(t[i] - t[i - 1] + 128);
    out.resize(compressBound(uLong(n)));
    thread_local ZlibLevel1 zlib(Z_DEFAULT_STRATEGY);
    return zlib.compress(filtered.data(), n, out.data(), out.size());
}

// A width x height image of one 32-bit channel (`isFloat`: FLOAT, else UINT) named `channel`,
// rows top to bottom, encoded in memory and written with writeEncoded.
bool writeExr(const std::string &path, int width, int height, const char *channel, bool isFloat, const void *pixels,
              std::string *err, ExrChunks *chunks = nullptr) {
    ExrSink sink;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &sink;
    init.write_fn = exrWrite;
    init.error_handler_fn = [](exr_const_context_t ctxt, exr_result_t code, const char *msg) {
        void *user = nullptr;
        if (exr_get_user_data(ctxt, &user) != EXR_ERR_SUCCESS || !user) return;
        std::string &e = static_cast<ExrSink *>(user)->error;
        if (e.empty()) e = std::string(exr_get_error_code_as_string(code)) + (msg ? std::string(": ") + msg : "");
    };
    exr_context_t ctx = nullptr;
    int part = 0;
    int32_t linesPerChunk = 0;
    auto fail = [&](exr_result_t code) {
        if (ctx) exr_finish(&ctx);
        if (err)
            *err = "cannot write image '" + path + "': OpenEXR: " +
                   (sink.error.empty() ? std::string(exr_get_error_code_as_string(code)) : sink.error);
        return false;
    };
    exr_result_t rv = exr_start_write(&ctx, path.c_str(), EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_part(ctx, nullptr, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS) rv = exr_initialize_required_attr_simple(ctx, part, width, height, EXR_COMPRESSION_ZIP);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_channel(ctx, part, channel, isFloat ? EXR_PIXEL_FLOAT : EXR_PIXEL_UINT,
                             EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_scanlines_per_chunk(ctx, part, &linesPerChunk);
    if (rv != EXR_ERR_SUCCESS) return fail(rv);
    thread_local std::vector<uint8_t> split, filtered, compressed;
    static_assert(std::endian::native == std::endian::little, "OpenEXR stores pixels little-endian");
    const size_t row = size_t(width) * 4;  // one 32-bit channel: the rows as they are in memory
    // The chunks of the image written before, when it has this one's size and type.
    const uint8_t *before = chunks && chunks->pixels && chunks->width == width && chunks->height == height &&
                                    chunks->isFloat == isFloat
                                ? static_cast<const uint8_t *>(chunks->pixels)
                                : nullptr;
    std::vector<std::vector<uint8_t>> written;
    for (int y = 0, k = 0; y < height; y += linesPerChunk, ++k) {
        const size_t at = size_t(y) * row;
        const uint8_t *raw = static_cast<const uint8_t *>(pixels) + at;
        const size_t n = size_t(std::min(linesPerChunk, height - y)) * row;
        std::vector<uint8_t> bytes;
        if (before && size_t(k) < chunks->bytes.size() && std::memcmp(raw, before + at, n) == 0) {
            bytes = std::move(chunks->bytes[size_t(k)]);
        } else {
            const size_t c = zipChunk(raw, n, split, filtered, compressed);
            if (c && c < n) bytes.assign(compressed.begin(), compressed.begin() + ptrdiff_t(c));
        }
        rv = bytes.empty() ? exr_write_scanline_chunk(ctx, part, y, raw, n)
                           : exr_write_scanline_chunk(ctx, part, y, bytes.data(), bytes.size());
        if (rv != EXR_ERR_SUCCESS) return fail(rv);
        if (chunks) written.push_back(std::move(bytes));
    }
    if (chunks) *chunks = ExrChunks{pixels, width, height, isFloat, std::move(written)};
    rv = exr_finish(&ctx);
    if (rv != EXR_ERR_SUCCESS) return fail(rv);
    return writeEncoded(path, sink.bytes, err);
}

// ---- Overdraw legend layout -------------------------------------------------------------------
// The legend is a row of swatches with their values below, right-aligned in a strip that extends
// the canvas below the image. All sizes are multiples of the font scale s:
//   strip height = margin 3s + swatch 6s + gap 2s + text 7s + margin 3s = 21s
//   cell width   = max(widest label, 7s) + gap 4s (the gap keeps "10" "11" apart from "1011")
constexpr Rgb8 kStripBackground{24, 24, 24};
constexpr Rgb8 kLegendText{255, 255, 255};
constexpr Rgb8 kSwatchOutline{160, 160, 160};

// Values shown in the legend: every value 0..cap when that is at most 17 swatches, otherwise
// 0, 1 and eight evenly spaced values up to cap.
std::vector<uint32_t> legendValues(uint32_t cap) {
    std::vector<uint32_t> v;
    if (cap <= 16) {
        for (uint32_t i = 0; i <= cap; ++i) v.push_back(i);
    } else {
        v = {0, 1};
        for (int k = 1; k <= 8; ++k) v.push_back(1 + uint32_t(std::lround(double(cap - 1) * k / 8.0)));
    }
    return v;
}

struct LegendLayout {
    int scale = 1, margin = 0, swatchH = 0, gap = 0, cellW = 0, stripH = 0, width = 0;
};
LegendLayout legendLayout(const std::vector<uint32_t> &values, int imageWidth) {
    LegendLayout L;
    L.scale = imageWidth >= 1024 ? 2 : 1;
    const int s = L.scale;
    int labelW = 0;
    for (uint32_t v : values) labelW = std::max(labelW, textWidth(std::to_string(v), s));
    L.margin = 3 * s;
    L.swatchH = 6 * s;
    L.gap = 4 * s;
    L.cellW = std::max(labelW, 7 * s) + L.gap;
    L.stripH = L.margin + L.swatchH + 2 * s + textHeight(s) + L.margin;
    L.width = int(values.size()) * L.cellW - L.gap;
    return L;
}

}  // namespace

bool writePngPalette(const std::string &path, const PaletteImage &image, std::string *err) {
    const int W = image.width, H = image.height;
    thread_local std::vector<uint8_t> index;  // kept from image to image: its pages stay mapped
    std::vector<png_color> palette;
    if (W <= 0 || H <= 0 || !paletteIndices(image, &index, &palette)) return writePngRgb8(path, W, H, image.rgb().data(), err);
    std::string bytes, why;
    if (!encodePngRows(W, H, PNG_COLOR_TYPE_PALETTE, palette, index.data(), size_t(W), &bytes, &why)) {
        if (err) *err = "cannot write image '" + path + "': " + why;
        return false;
    }
    return writeEncoded(path, bytes, err);
}

bool writePngRgb8(const std::string &path, int width, int height, const uint8_t *rgb, std::string *err) {
    return writePng(path, width, height, 3, rgb, err);
}

bool writeExrUint32(const std::string &path, int width, int height, const uint32_t *values, const char *channel,
                    std::string *err, ExrChunks *chunks) {
    return writeExr(path, width, height, channel, false, values, err, chunks);
}

// ---- Color mappings ---------------------------------------------------------------------------

// Depth complexity ramp: a fixed piecewise-linear ramp through blue, cyan, green, yellow, red and
// white (lightness rises along it, so a gray-scale print still orders the values). A value v >= 1
// sits at t = (min(v, cap) - 1) / (cap - 1) in [0, 1]; each channel is interpolated between the two
// stops around t and rounded. 0 fragments (nothing drawn) is black, outside the ramp.
Rgb8 overdrawColor(uint32_t fragments, uint32_t cap) {
    struct Stop {
        double t;
        Rgb8 c;
    };
    static constexpr Stop kStops[] = {
        {0.00, {32, 64, 255}},  {0.25, {0, 200, 255}}, {0.50, {48, 220, 48}},
        {0.75, {255, 220, 0}},  {0.90, {255, 32, 0}},  {1.00, {255, 255, 255}},
    };
    if (fragments == 0) return {0, 0, 0};
    const double t = cap <= 1 ? 0.0 : double(std::min(fragments, cap) - 1) / double(cap - 1);
    for (size_t i = 1; i < std::size(kStops); ++i) {
        if (t > kStops[i].t) continue;
        const Stop &a = kStops[i - 1], &b = kStops[i];
        const double u = (t - a.t) / (b.t - a.t);
        auto lerp = [u](uint8_t x, uint8_t y) { return uint8_t(std::lround(x + (double(y) - x) * u)); };
        return {lerp(a.c.r, b.c.r), lerp(a.c.g, b.c.g), lerp(a.c.b, b.c.b)};
    }
    return kStops[std::size(kStops) - 1].c;
}

// Depth visualization: perspective depth spans orders of magnitude (0.1 .. 1000), so a linear ramp
// would put everything near the camera in one gray. On a log scale equal depth *ratios* get equal
// gray steps:  t = (ln d - ln dMin) / (ln dMax - ln dMin) in [0, 1],
//              gray = round(255 - t * (255 - kDepthPngFarGray)).
// The nearest surface of the view is white, the farthest kDepthPngFarGray (kept above 0 so that the
// farthest geometry is still distinguishable from the black background). dMin == dMax: all white.
void depthRange(const std::vector<double> &depth, double *dMin, double *dMax) {
    // In locals: through the pointers every pixel would store and reload both (they may alias the
    // buffer, as far as the compiler knows), 2.4 ns a pixel.
    double lo = INFINITY, hi = -INFINITY;
    for (double d : depth)
        if (std::isfinite(d) && d > 0) {
            lo = std::min(lo, d);
            hi = std::max(hi, d);
        }
    *dMin = lo;
    *dMax = hi;
}

uint8_t depthGray(double d, double dMin, double dMax) { return DepthGrayScale(dMin, dMax)(d); }

// The grays of a whole buffer without a logarithm per pixel. Every finite positive depth lies in
// [dMin, dMax] (the buffer's own range), cut into at most 2^14 buckets of equal steps of the
// doubles' bit patterns (positive doubles order like their bits); a bucket whose depths all map
// to one gray stores it, and only the depths of the other buckets (those holding a gray's
// boundary: about 1% of them) take the logarithm. A bucket's depths share one gray when the gray
// just outside its ends, a window rho further out, is the same at both: the gray of the computed
// value is monotone (non-increasing) in d wherever log is, since the rest is a subtraction and a
// division by constants, a multiplication, a subtraction, an addition and a truncation, each
// monotone under rounding; glibc's log is within 0.52 ulp of log d (its implementation's stated
// bound), taken as 4 ulps (8u |log d| <= 8u L, L the largest |log| involved), so for d' = d (1 + r)
// the computed logs keep their order once log(1 + r) >= r / 2 exceeds 16u L: rho = 32u L.
std::vector<uint8_t> depthGrays(const std::vector<double> &depth, double *dMin, double *dMax) {
    double lo, hi;
    depthRange(depth, &lo, &hi);
    if (dMin) *dMin = lo;
    if (dMax) *dMax = hi;
    const DepthGrayScale scale(lo, hi);
    std::vector<uint8_t> g(depth.size());
    if (!scale.valid || !scale.spread) {  // no logarithm to spare
        for (size_t i = 0; i < depth.size(); ++i) g[i] = scale(depth[i]);
        return g;
    }
    auto bits = [](double d) {
        uint64_t b;
        std::memcpy(&b, &d, sizeof b);
        return b;
    };
    auto fromBits = [](uint64_t b) {
        double d;
        std::memcpy(&d, &b, sizeof d);
        return d;
    };
    constexpr int kBucketBits = 14;
    constexpr uint16_t kUnresolved = 0xFFFF;
    const uint64_t base = bits(lo), span = bits(hi) - base + 1;
    const int shift = std::max(0, int(std::bit_width(span)) - kBucketBits);
    const size_t buckets = size_t(((span - 1) >> shift) + 1);
    const double L = std::max({1.0, std::fabs(std::log(lo)), std::fabs(std::log(hi))}) + 1;
    const double rho = 32 * 0x1p-53 * L;
    std::vector<uint16_t> table(buckets, kUnresolved);
    for (size_t b = 0; b < buckets; ++b) {
        const double first = fromBits(base + (uint64_t(b) << shift)), end = fromBits(base + (uint64_t(b + 1) << shift));
        const double below = std::nextafter(first / (1 + 2 * rho), 0.0);
        const double above = std::nextafter(end * (1 + 2 * rho), INFINITY);
        if (!std::isfinite(above)) continue;
        const uint8_t a = scale(below), z = scale(above);
        if (a == z) table[b] = a;
    }
    for (size_t i = 0; i < depth.size(); ++i) {
        const double d = depth[i];
        if (!(d > 0) || !std::isfinite(d)) {
            g[i] = 0;  // background (as scale(d))
            continue;
        }
        const uint16_t t = table[size_t((bits(d) - base) >> shift)];
        g[i] = t != kUnresolved ? uint8_t(t) : scale(d);
    }
    return g;
}

std::vector<uint8_t> depthGraysFrom(const std::vector<double> &depth, const std::vector<double> &known,
                                    const std::vector<uint8_t> &knownGrays, double knownMin, double knownMax) {
    const size_t n = depth.size();
    if (known.size() != n || knownGrays.size() != n || n > UINT32_MAX) return depthGrays(depth);
    // The grays copied and the pixels whose depths differ listed. depth has known's range when no
    // differing pixel has a finite positive depth outside it and none held one of its ends in known:
    // every other pixel has known's depth, and known's ends are then met at such pixels.
    std::vector<uint8_t> g(knownGrays);
    thread_local std::vector<uint32_t> differ;
    differ.clear();
    const double *__restrict a = depth.data(), *__restrict b = known.data();
    for (size_t i = 0; i < n; ++i)
        if (std::memcmp(&a[i], &b[i], sizeof a[i]) != 0) [[unlikely]]
            differ.push_back(uint32_t(i));
    for (const uint32_t i : differ) {
        const double d = a[i];
        const bool inside = !(d > 0 && d < INFINITY) || (d >= knownMin && d <= knownMax);
        if (!inside || b[i] == knownMin || b[i] == knownMax) return depthGrays(depth);
    }
    const DepthGrayScale scale(knownMin, knownMax);
    for (const uint32_t i : differ) g[i] = scale(a[i]);
    return g;
}

// ---- Writing ----------------------------------------------------------------------------------

bool writeViewImages(const ViewResult &view, const std::string &dir, const std::string &baseName,
                     std::string *err, ImageSet set) {
    auto want = [&](const char *key) { return imageWritten(set, key); };
    if (set == ImageSet::none) return true;
    const ZBuffer &zb = view.buffer;
    const int W = zb.width, H = zb.height;
    const size_t n = size_t(std::max(W, 0)) * size_t(std::max(H, 0));
    if (W <= 0 || H <= 0 || zb.depth.size() != n || zb.id.size() != n || zb.fragments.size() != n) {
        if (err)
            *err = "view '" + view.spec.name + "': no per-pixel buffers of " + std::to_string(W) + "x" +
                   std::to_string(H) + " pixels to write images from (were they released before writing?)";
        return false;
    }
    const ViewImageNames names = viewImageNames(baseName);
    const std::string prefix = dir.empty() ? std::string() : (dir.back() == '/' ? dir : dir + "/");
    // The grays of the z-buffer's and the reference's depths, computed once for every image drawn
    // over them (depthGrays), when the first such image is written; the reference's from the
    // z-buffer's when those are at hand (depthGraysFrom: the two buffers differ at a few pixels).
    std::optional<std::vector<uint8_t>> zGraysMemo, refGraysMemo;
    double zMin = 0, zMax = 0;
    auto zGrays = [&]() -> const std::vector<uint8_t> * {
        if (!zGraysMemo) zGraysMemo = depthGrays(zb.depth, &zMin, &zMax);
        return &*zGraysMemo;
    };
    auto refGrays = [&]() -> const std::vector<uint8_t> * {
        const std::vector<double> &depth = view.audit->reference.depth;
        if (!refGraysMemo)
            refGraysMemo = zGraysMemo ? depthGraysFrom(depth, zb.depth, *zGraysMemo, zMin, zMax) : depthGrays(depth);
        return &*refGraysMemo;
    };

    // BASE.depth.exr: view depth as float, +inf where nothing was drawn.
    if (want("depth_exr")) {
        UninitVector<float> z(n);  // every element written below: no clear first
        for (size_t i = 0; i < n; ++i) z[i] = float(zb.depth[i]);
        if (!writeExr(prefix + names.depthExr, W, H, "Z", true, z.data(), err)) return false;
    }

    // BASE.depth.png: log-scaled gray between the view's nearest and farthest finite depth.
    if (want("depth_png")) {
        if (!writePng(prefix + names.depthPng, W, H, 1, zGrays()->data(), err)) return false;
    }

    // BASE.overdraw.png: heatmap of fragments per pixel, scale capped at max(8, most fragments), with
    // the legend in a strip below the image (the canvas widens if the legend is wider than the image).
    if (want("overdraw_png")) {
        uint32_t maxFragments = 0;
        for (uint16_t f : zb.fragments) maxFragments = std::max<uint32_t>(maxFragments, f);
        const uint32_t cap = std::max<uint32_t>(8, maxFragments);
        const std::vector<uint32_t> values = legendValues(cap);
        const LegendLayout L = legendLayout(values, W);
        const int CW = std::max(W, L.width + 2 * L.margin), CH = H + L.stripH;
        PaletteImage img(CW, CH, kStripBackground);
        // One ramp color per fragment count, looked up per pixel (overdrawColor searches the stops
        // and rounds three channels).
        std::vector<uint16_t> codeOf(size_t(maxFragments) + 1);
        for (uint32_t f = 0; f <= maxFragments; ++f) codeOf[f] = img.codeOf(overdrawColor(f, cap));
        for (int y = 0; y < H; ++y) {
            const uint16_t *__restrict f = zb.fragments.data() + size_t(y) * size_t(W);
            uint16_t *__restrict row = img.code.data() + size_t(y) * size_t(CW);
            for (int x = 0; x < W; ++x) row[x] = codeOf[f[x]];
        }
        // Legend, right-aligned: swatch i spans [x_i, x_i + cellW - gap) x [top, top + swatchH), with a
        // one-cell outline so that the black "0" swatch shows on the dark strip; its label is centered
        // below it.
        const int s = L.scale;
        const int x0 = CW - L.margin - L.width, top = H + L.margin;
        for (size_t i = 0; i < values.size(); ++i) {
            const int xi = x0 + int(i) * L.cellW, sw = L.cellW - L.gap;
            img.fill(xi, top, xi + sw, top + L.swatchH, kSwatchOutline);
            img.fill(xi + s, top + s, xi + sw - s, top + L.swatchH - s, overdrawColor(values[i], cap));
            const std::string label = std::to_string(values[i]);
            const int lx = xi + (sw - textWidth(label, s)) / 2, ly = top + L.swatchH + 2 * s;
            img.text(lx, ly, label, kLegendText, s);
        }
        if (!writePngPalette(prefix + names.overdrawPng, img, err)) return false;
    }

    // BASE.ids.exr: 1 + visible source triangle index as UINT32 (OpenEXR's 32-bit unsigned pixel
    // type holds every id exactly, unlike a float channel, which would round ids above 2^24).
    ExrChunks idChunks;  // the z-buffer's ids, for the ray caster's (mostly the same rows)
    if (want("ids_exr")) {
        if (!writeExr(prefix + names.idsExr, W, H, "id", false, zb.id.data(), err, &idChunks)) return false;
    }

    // BASE.zfight.png: the z-fighting hotspots (reports/zfight_image.h).
    if (view.zfight.ran() && want("zfight_png") && !writeZFightImage(*view.zfight, zb, prefix + names.zfightPng, err, zGrays()))
        return false;
    // BASE.culling.png: the reference visibility colored by each pixel's fate (reports/audit_images.h).
    if (view.audit.ran() && want("culling_png") && !writeCullingImage(view.audit->reference, view.audit->cull, prefix + names.cullingPng, err, refGrays()))
        return false;
    // Draw orders: painter's errors, overdraw by order, the A-buffer composite (reports/ordering_images.h).
    if (view.ordering.ran() && view.audit.ran()) {
        const OrderingImageNames on = orderingImageNames(names.base);
        if (want("painter_errors_png") &&
            !writePainterErrorsImage(view.audit->reference, view.ordering->painter, prefix + on.painterErrorsPng, err,
                                     refGrays()))
            return false;
        if (want("overdraw_order_png") &&
            !writeOverdrawByOrderChart(view.ordering->overdrawByOrder, prefix + on.overdrawOrderPng, err))
            return false;
        if (view.ordering->abufferRan && want("abuffer_png") &&
            !writeABufferImage(view.ordering->abuffer, prefix + on.abufferPng, err))
            return false;
    }
    // The raycast stage: its ids, and where it disagrees with the z-buffer (reports/audit_images.h).
    if (view.raycast.ran()) {
        const RaycastImage &image = view.raycast->image;
        if (want("raycast_ids_exr") && !writeRaycastIds(image.width, image.height, image.id, prefix + names.raycastIdsExr, err, &idChunks))
            return false;
        if (want("raycast_diff_png") && !writeRaycastDiffImage(zb, view.raycast->crossCheck, prefix + names.raycastDiffPng, err, zGrays()))
            return false;
    }
    // Secondary rays: one shadow image per light, the depth of the ray trees (reports/effects_images.h).
    if (view.effects.ran()) {
        for (size_t l = 0; l < view.effects->lights.size() && want("shadow_png"); ++l)
            if (!writeShadowImage(*view.effects, l, zb, prefix + shadowImageName(names, l, view), err, zGrays()))
                return false;
        if (want("secondary_png") && !writeSecondaryImage(*view.effects, zb, prefix + names.secondaryPng, err, zGrays()))
            return false;
    }
    return true;
}

bool writeViewImages(const ViewResult &view, const std::string &dir, std::string *err) {
    return writeViewImages(view, dir, sanitizeFileName(view.spec.name), err);
}

bool writeAllViewImages(const AnalysisResult &result, const std::string &dir, std::string *err) {
    const std::vector<std::string> bases = imageBaseNames(result.views);
    for (size_t i = 0; i < result.views.size(); ++i)
        if (!writeViewImages(result.views[i], dir, bases[i], err)) return false;
    return true;
}

}  // namespace va
