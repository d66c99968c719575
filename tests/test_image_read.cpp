// readImage (reports/image_read.cpp: libpng and OpenEXR) against the samples written: PNGs of every
// channel count in 8 and 16 bits, visaudit's own palette and RGB PNGs, EXRs of float, uint and half
// channels, channels out of order, tiles, and a data window off the origin. (It replaced
// OpenImageIO, and its answers are OpenImageIO's for these files: the channel names, the first
// channel's type, every channel in it.) And files that are no image, or a truncated one: a message
// naming the file, never a crash.
#include <gtest/gtest.h>

#include <fstream>

#include <zlib.h>

#include "reports/report.h"
#include "tests/image_files.h"
#include "tests/temp_dir_test.h"

using namespace va;
using namespace va::test;

namespace {

class ImageRead : public va::testing_util::TempDirTest {
  protected:
    ImageRead() : TempDirTest("imageread") {}
    std::string path(const std::string &name) const { return (dir_ / name).string(); }
};

// Deterministic samples: varied, so a swapped channel, row or byte shows.
template <typename T>
std::vector<T> samples(size_t n, uint64_t seed) {
    std::vector<T> v(n);
    uint64_t s = seed;
    for (size_t i = 0; i < n; ++i) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        if constexpr (std::is_floating_point_v<T>) v[i] = T(double(s >> 11) * 0x1p-53 * 1000.0 - 10.0);
        else v[i] = T(s >> 40);
    }
    return v;
}

ImageData read(const std::string &path) {
    ImageData im;
    std::string err;
    EXPECT_TRUE(readImage(path, &im, &err)) << err;
    return im;
}

}  // namespace

TEST_F(ImageRead, PngsAsWritten) {
    const int W = 37, H = 23;  // odd sizes: no row happens to align
    const std::vector<std::string> names[5] = {{}, {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    for (int channels = 1; channels <= 4; ++channels) {
        SCOPED_TRACE(channels);
        const size_t n = size_t(W) * H * size_t(channels);
        const std::string base = path("c") + std::to_string(channels);
        const std::vector<uint8_t> u8 = samples<uint8_t>(n, 7 + channels);
        const std::vector<uint16_t> u16 = samples<uint16_t>(n, 11 + channels);
        ASSERT_TRUE(writePngFile(base + "-8.png", W, H, channels, 8, u8.data()));
        ASSERT_TRUE(writePngFile(base + "-16.png", W, H, channels, 16, u16.data()));
        const ImageData a = read(base + "-8.png"), b = read(base + "-16.png");
        EXPECT_EQ(a.width, W);
        EXPECT_EQ(a.height, H);
        EXPECT_EQ(a.channelNames, names[channels]);
        EXPECT_EQ(a.pixelType, "uint8");
        EXPECT_EQ(a.u8, u8);
        EXPECT_EQ(b.channelNames, names[channels]);
        EXPECT_EQ(b.pixelType, "uint16");
        EXPECT_EQ(b.u16, u16);  // 16-bit samples unscaled, in the machine's byte order
    }
    // visaudit's own PNGs: a palette (few colors) and RGB (more than 256).
    std::vector<uint8_t> few(size_t(W) * H * 3), many = samples<uint8_t>(size_t(W) * H * 3, 3);
    for (size_t i = 0; i < few.size(); ++i) few[i] = uint8_t((i / 3 % 5) * 40 + i % 3);
    std::string err;
    ASSERT_TRUE(writePngRgb8(path("palette.png"), W, H, few.data(), &err)) << err;
    ASSERT_TRUE(writePngRgb8(path("rgb.png"), W, H, many.data(), &err)) << err;
    for (const auto &[name, rgb] : {std::pair{"palette.png", &few}, std::pair{"rgb.png", &many}}) {
        const ImageData im = read(path(name));
        EXPECT_EQ(im.channelNames, names[3]) << name;
        EXPECT_EQ(im.u8, *rgb) << name;  // a palette expanded to the pixels written
    }
}

TEST_F(ImageRead, ExrsAsWritten) {
    const int W = 29, H = 17;
    const size_t n = size_t(W) * H;
    const std::vector<float> z = samples<float>(n, 1), rgba = samples<float>(4 * n, 3);
    const std::vector<float> mixed = samples<float>(5 * n, 4);
    const std::vector<uint32_t> id = samples<uint32_t>(n, 2);
    ASSERT_TRUE(writeExrFile(path("z.exr"), W, H, {"Z"}, Imf::FLOAT, z.data()));
    ASSERT_TRUE(writeExrFile(path("id.exr"), W, H, {"id"}, Imf::UINT, id.data()));
    ASSERT_TRUE(writeExrFile(path("rgba-half.exr"), W, H, {"R", "G", "B", "A"}, Imf::HALF, rgba.data()));
    // Written as Z, A, B, G, R (the file keeps them alphabetically: A, B, G, R, Z), a data window
    // off the origin; read as R, G, B, A, Z.
    ASSERT_TRUE(writeExrFile(path("mixed.exr"), W, H, {"Z", "A", "B", "G", "R"}, Imf::FLOAT, mixed.data(), 5, -3));
    // Tiles (16 x 8, the last ones partial) instead of scanlines, off the origin too.
    ASSERT_TRUE(writeExrFile(path("tiled.exr"), W, H, {"Z"}, Imf::FLOAT, z.data(), -2, 7, 16, 8));
    {
        const ImageData im = read(path("z.exr"));
        EXPECT_EQ(im.channelNames, std::vector<std::string>{"Z"});
        EXPECT_EQ(im.pixelType, "float");
        EXPECT_EQ(im.f32, z);
    }
    {
        const ImageData im = read(path("tiled.exr"));
        EXPECT_EQ(im.channelNames, std::vector<std::string>{"Z"});
        EXPECT_EQ(im.width, W);
        EXPECT_EQ(im.height, H);
        EXPECT_EQ(im.f32, z);
    }
    {
        const ImageData im = read(path("id.exr"));
        EXPECT_EQ(im.channelNames, std::vector<std::string>{"id"});
        EXPECT_EQ(im.pixelType, "uint");
        EXPECT_EQ(im.u32, id);
    }
    {
        const ImageData im = read(path("rgba-half.exr"));
        EXPECT_EQ(im.channelNames, (std::vector<std::string>{"R", "G", "B", "A"}));
        EXPECT_EQ(im.pixelType, "float");
        ASSERT_EQ(im.f32.size(), rgba.size());
        for (size_t i = 0; i < rgba.size(); ++i) ASSERT_EQ(im.f32[i], float(half(rgba[i]))) << i;
    }
    {
        const ImageData im = read(path("mixed.exr"));
        EXPECT_EQ(im.channelNames, (std::vector<std::string>{"R", "G", "B", "A", "Z"}));
        EXPECT_EQ(im.width, W);
        EXPECT_EQ(im.height, H);
        ASSERT_EQ(im.f32.size(), mixed.size());
        const int from[5] = {4, 3, 2, 1, 0};  // R G B A Z in the written order Z A B G R
        for (size_t p = 0; p < n; ++p)
            for (int c = 0; c < 5; ++c) ASSERT_EQ(im.f32[5 * p + size_t(c)], mixed[5 * p + size_t(from[c])]) << p;
    }
}

TEST_F(ImageRead, NotAnImageOrCutShortIsAMessage) {
    std::string err;
    ImageData im;
    EXPECT_FALSE(readImage(path("absent.png"), &im, &err));
    EXPECT_NE(err.find("absent.png"), std::string::npos) << err;
    {
        std::ofstream(path("text.png")) << "not an image at all\n";
    }
    EXPECT_FALSE(readImage(path("text.png"), &im, &err));
    EXPECT_NE(err.find("neither a PNG nor an OpenEXR file"), std::string::npos) << err;
    // PNG headers claiming 60000 x 60000 pixels (more than visaudit reads) and 8000 x 8000 (more than
    // the file's few bytes can hold: deflate stores at most 1032 bytes a byte), and no data: refused
    // before 3.6 GB or 64 MB are allocated.
    for (const auto &[side, says] : {std::pair{60000u, "2^27 pixels"}, std::pair{8000u, "more image data than"}}) {
        auto be32 = [](std::string &s, uint32_t v) {
            for (int k = 3; k >= 0; --k) s += char(v >> (8 * k) & 0xFF);
        };
        std::string png("\x89PNG\r\n\x1a\n", 8), ihdr = "IHDR";
        be32(ihdr, side);
        be32(ihdr, side);
        ihdr += std::string("\x08\x00\x00\x00\x00", 5);  // 8-bit gray, no interlace
        be32(png, 13);
        png += ihdr;
        be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef *>(ihdr.data()), uInt(ihdr.size()))));
        const std::string idat("IDAT\x78\x01", 6);  // a zlib header only: the header is read up to here
        be32(png, 2);
        png += idat;
        be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef *>(idat.data()), uInt(idat.size()))));
        std::ofstream(path("huge.png"), std::ios::binary) << png;
        EXPECT_FALSE(readImage(path("huge.png"), &im, &err));
        EXPECT_NE(err.find(says), std::string::npos) << err;
    }
    // Every prefix of a real PNG and EXR: refused with the file's name, never a crash.
    const int W = 40, H = 30;
    std::vector<uint8_t> rgb = samples<uint8_t>(size_t(W) * H * 3, 9);
    ASSERT_TRUE(writePngRgb8(path("whole.png"), W, H, rgb.data(), &err)) << err;
    const std::vector<float> z = samples<float>(size_t(W) * H, 5);
    ASSERT_TRUE(writeExrFile(path("whole.exr"), W, H, {"Z"}, Imf::FLOAT, z.data()));
    for (const char *name : {"whole.png", "whole.exr"}) {
        std::ifstream f(path(name), std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        ASSERT_GT(bytes.size(), 100u);
        for (size_t cut = 0; cut < bytes.size(); cut += 1 + cut / 8) {
            const std::string cutPath = path("cut-" + std::to_string(cut) + "-" + name);
            std::ofstream(cutPath, std::ios::binary).write(bytes.data(), std::streamsize(cut));
            EXPECT_FALSE(readImage(cutPath, &im, &err)) << cutPath;
            EXPECT_NE(err.find(cutPath), std::string::npos) << err;
        }
    }
}
