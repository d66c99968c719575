// Reading images (readImage, reports/report.h): PNG through libpng, EXR through OpenEXR, both of
// which visaudit links for writing them. OpenImageIO read them until issue 18: loading it and the
// ~500 libraries it needs cost 0.3 s at every start of visaudit (a third of the demo's analyze
// run), for a reader that only ever sees these two formats.
#include <algorithm>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <png.h>

#include "reports/report.h"

namespace va {

namespace {

// The most pixels read (16,384 x 8,192) and samples (pixels x channels: 1 GiB of floats): a header
// claiming more is refused before anything is allocated for it (a damaged or hostile file must not
// take the machine's memory).
constexpr uint64_t kMaxPixels = uint64_t(1) << 27, kMaxSamples = uint64_t(1) << 28;

// What readPng changes while libpng may jump back to its setjmp: the caller's, so that nothing of
// readPng's own frame changes between the setjmp and a jump (such locals would be indeterminate
// after it). libpng's errors keep their message here and take the jump.
struct PngRead {
    char message[256] = "";
    std::vector<png_bytep> rows;
};
[[noreturn]] void pngError(png_structp png, png_const_charp msg) {
    auto *e = static_cast<PngRead *>(png_get_error_ptr(png));
    std::snprintf(e->message, sizeof e->message, "%s", msg ? msg : "libpng error");
    png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}

// 8- or 16-bit samples in the file's channels: a palette as RGB (RGBA with a transparency chunk),
// gray below 8 bits scaled to 8, 16-bit samples in the machine's byte order. Channels are named as
// OpenImageIO named them: Y, Y A, R G B, R G B A. libpng reports errors by longjmp to the setjmp
// below; what changes after it is the caller's (`d`, `state`). `fileSize` bounds what the file can
// hold: deflate encodes at most 1032 bytes per byte, so a header claiming more image data than that
// is refused before anything is allocated for it.
bool readPng(std::FILE *f, uint64_t fileSize, const std::string &path, ImageData *d, PngRead *state,
             std::string *err) {
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, state, pngError, pngWarning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_read_struct(&png, &info, nullptr);
        *err = "cannot read image '" + path + "': libpng could not allocate its reader";
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        *err = "cannot read image '" + path + "': " + state->message;
        return false;
    }
    png_init_io(png, f);
    png_read_info(png, info);
    if (uint64_t(png_get_image_width(png, info)) * png_get_image_height(png, info) > kMaxPixels)
        png_error(png, "its header claims more than 2^27 pixels (16384 x 8192), more than visaudit reads");
    const int colorType = png_get_color_type(png, info);
    const int bitDepth = png_get_bit_depth(png, info);
    if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (colorType == PNG_COLOR_TYPE_GRAY && bitDepth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    if (bitDepth == 16) png_set_swap(png);  // big-endian in the file
    // The filtered rows as stored (a filter byte each), before any expansion.
    const uint64_t stored = uint64_t(png_get_image_height(png, info)) * (1 + png_get_rowbytes(png, info));
    if (stored > 1032 * fileSize + 1024)
        png_error(png, "its header claims more image data than a file of this size can hold (cut short?)");
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    const int channels = png_get_channels(png, info), depth = png_get_bit_depth(png, info);
    static const std::vector<std::string> names[5] = {{}, {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    if (channels < 1 || channels > 4 || (depth != 8 && depth != 16))
        png_error(png, "unexpected channels or bit depth after expansion");
    d->width = int(w);
    d->height = int(h);
    d->channelNames = names[channels];
    const size_t count = size_t(w) * size_t(h) * size_t(channels);
    unsigned char *base;
    if (depth == 8) {
        d->pixelType = "uint8";
        d->u8.resize(count);
        base = d->u8.data();
    } else {
        d->pixelType = "uint16";
        d->u16.resize(count);
        base = reinterpret_cast<unsigned char *>(d->u16.data());
    }
    const size_t rowBytes = size_t(w) * size_t(channels) * size_t(depth / 8);
    if (png_get_rowbytes(png, info) != rowBytes) png_error(png, "unexpected row size after expansion");
    state->rows.resize(h);
    for (png_uint_32 y = 0; y < h; ++y) state->rows[y] = base + size_t(y) * rowBytes;
    png_read_image(png, state->rows.data());
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return true;
}

// An EXR's first part (scanlines or tiles): every channel in the first channel's type (uint32 as
// "uint", half and float as "float"), channels in OpenImageIO's order (R, G, B, A first, then the
// others in the file's, alphabetical, order), the data window as the image.
bool readExr(const std::string &path, ImageData *d, std::string *err) {
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header &header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        const long long w = (long long)dw.max.x - dw.min.x + 1, h = (long long)dw.max.y - dw.min.y + 1;
        if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > kMaxPixels) {
            *err = "cannot read image '" + path + "': its data window is empty or claims more than 2^27 pixels " +
                   "(16384 x 8192), more than visaudit reads";
            return false;
        }
        std::vector<std::string> names;
        for (const char *first : {"R", "G", "B", "A"})
            if (header.channels().findChannel(first)) names.push_back(first);
        for (auto c = header.channels().begin(); c != header.channels().end(); ++c)
            if (std::find(names.begin(), names.end(), c.name()) == names.end()) names.push_back(c.name());
        if (names.empty()) {
            *err = "cannot read image '" + path + "': it has no channels";
            return false;
        }
        if (uint64_t(w) * uint64_t(h) * names.size() > kMaxSamples) {
            *err = "cannot read image '" + path + "': its " + std::to_string(names.size()) +
                   " channels of that many pixels are more than 2^28 samples, more than visaudit reads";
            return false;
        }
        const Imf::PixelType type = header.channels().findChannel(names[0])->type == Imf::UINT ? Imf::UINT : Imf::FLOAT;
        const size_t C = names.size(), count = size_t(w) * size_t(h) * C, sample = 4;
        char *base;
        if (type == Imf::UINT) {
            d->pixelType = "uint";
            d->u32.resize(count);
            base = reinterpret_cast<char *>(d->u32.data());
        } else {
            d->pixelType = "float";
            d->f32.resize(count);
            base = reinterpret_cast<char *>(d->f32.data());
        }
        // Slices address pixel (x, y) of the data window at base + (y - min.y) * yStride + (x - min.x) * xStride.
        const size_t xStride = C * sample, yStride = size_t(w) * xStride;
        const ptrdiff_t origin = -(ptrdiff_t(dw.min.x) * ptrdiff_t(xStride) + ptrdiff_t(dw.min.y) * ptrdiff_t(yStride));
        Imf::FrameBuffer fb;
        for (size_t c = 0; c < C; ++c)
            fb.insert(names[c], Imf::Slice(type, base + origin + ptrdiff_t(c * sample), xStride, yStride));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        d->width = int(w);
        d->height = int(h);
        d->channelNames = std::move(names);
        return true;
    } catch (const std::exception &e) {
        *err = "cannot read image '" + path + "': " + e.what();
        return false;
    }
}

}  // namespace

bool readImage(const std::string &path, ImageData *out, std::string *err) {
    std::string why;
    const std::unique_ptr<std::FILE, int (*)(std::FILE *)> f(std::fopen(path.c_str(), "rb"), std::fclose);
    if (!f) {
        if (err) *err = "cannot read image '" + path + "': " + std::strerror(errno);
        return false;
    }
    std::fseek(f.get(), 0, SEEK_END);
    const long size = std::ftell(f.get());
    std::rewind(f.get());
    unsigned char magic[8] = {};
    const size_t got = std::fread(magic, 1, sizeof magic, f.get());
    static const unsigned char pngMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static const unsigned char exrMagic[4] = {0x76, 0x2f, 0x31, 0x01};
    ImageData d;
    bool ok;
    if (got == 8 && std::memcmp(magic, pngMagic, 8) == 0) {
        std::rewind(f.get());
        PngRead state;
        ok = readPng(f.get(), uint64_t(std::max(size, 0L)), path, &d, &state, &why);
    } else if (got >= 4 && std::memcmp(magic, exrMagic, 4) == 0) {
        ok = readExr(path, &d, &why);
    } else {
        why = "cannot read image '" + path + "': neither a PNG nor an OpenEXR file (visaudit reads those two)";
        ok = false;
    }
    if (!ok) {
        if (err) *err = why;
        return false;
    }
    *out = std::move(d);
    return true;
}

}  // namespace va
