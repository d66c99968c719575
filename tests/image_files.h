// Test inputs in image formats visaudit reads but does not write itself: PNGs of any channel count in
// 8 or 16 bits (libpng) and EXRs of uint, half or float channels with any names and data window
// (OpenEXR's C++ API). Samples are interleaved, rows top-down, as readImage returns them.
#pragma once

#include <csetjmp>
#include <cstdint>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <png.h>

namespace va::test {

// 1-4 channels (gray, gray + alpha, RGB, RGBA) of 8 or 16 bits (`samples` as uint8_t or uint16_t).
inline bool writePngFile(const std::string &path, int width, int height, int channels, int bitDepth,
                         const void *samples) {
    static const int types[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                 PNG_COLOR_TYPE_RGB_ALPHA};
    std::FILE *f = std::fopen(path.c_str(), "wb");
    if (!f) return false;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        std::fclose(f);
        return false;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), bitDepth, types[channels], PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (bitDepth == 16) png_set_swap(png);  // the samples in the machine's (little-endian) order
    const size_t rowBytes = size_t(width) * size_t(channels) * size_t(bitDepth / 8);
    for (int y = 0; y < height; ++y)
        png_write_row(png, static_cast<png_const_bytep>(samples) + size_t(y) * rowBytes);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return std::fclose(f) == 0;
}

// Channels `names` of one type (Imf::UINT: uint32_t samples; HALF or FLOAT: float samples, stored as
// half or float), ZIP compressed, the data window's top-left corner at (x0, y0); scanlines, or tiles
// of tileWidth x tileHeight when those are positive.
inline bool writeExrFile(const std::string &path, int width, int height, const std::vector<std::string> &names,
                         Imf::PixelType type, const void *samples, int x0 = 0, int y0 = 0, int tileWidth = 0,
                         int tileHeight = 0) {
    try {
        Imf::Header header(Imath::Box2i({0, 0}, {width - 1, height - 1}),
                           Imath::Box2i({x0, y0}, {x0 + width - 1, y0 + height - 1}));
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const std::string &n : names) header.channels().insert(n, Imf::Channel(type));
        // Halves from the float samples, through a buffer of their own.
        const size_t C = names.size(), count = size_t(width) * size_t(height) * C;
        std::vector<half> halves(type == Imf::HALF ? count : 0);
        for (size_t i = 0; i < halves.size(); ++i) halves[i] = half(static_cast<const float *>(samples)[i]);
        const char *base = type == Imf::HALF ? reinterpret_cast<const char *>(halves.data())
                                             : static_cast<const char *>(samples);
        const size_t sample = type == Imf::HALF ? 2 : 4, xStride = C * sample, yStride = size_t(width) * xStride;
        const ptrdiff_t origin = -(ptrdiff_t(x0) * ptrdiff_t(xStride) + ptrdiff_t(y0) * ptrdiff_t(yStride));
        Imf::FrameBuffer fb;
        for (size_t c = 0; c < C; ++c)
            fb.insert(names[c], Imf::Slice(type, const_cast<char *>(base) + origin + ptrdiff_t(c * sample), xStride,
                                           yStride));
        if (tileWidth > 0 && tileHeight > 0) {
            header.setTileDescription(Imf::TileDescription(unsigned(tileWidth), unsigned(tileHeight), Imf::ONE_LEVEL));
            Imf::TiledOutputFile file(path.c_str(), header);
            file.setFrameBuffer(fb);
            file.writeTiles(0, file.numXTiles() - 1, 0, file.numYTiles() - 1);
            return true;
        }
        Imf::OutputFile file(path.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(height);
        return true;
    } catch (const std::exception &) {
        return false;
    }
}

}  // namespace va::test
