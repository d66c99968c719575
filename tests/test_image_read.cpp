// readImage (reports/image_read.cpp: libpng and OpenEXR) against OpenImageIO, which read the same
// files before: PNGs of every channel count in 8 and 16 bits, visaudit's palette PNGs, EXRs of
// float, uint and half channels, channels out of order and a data window off the origin. And
// files that are no image, or a truncated one: a message naming the file, never a crash.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include <OpenImageIO/imageio.h>
#include <zlib.h>

#include "reports/report.h"

using namespace va;
namespace fs = std::filesystem;

namespace {

struct ScratchDir {
    std::string path;
    ScratchDir() {
        std::string t = (fs::temp_directory_path() / "visaudit-imageread-XXXXXX").string();
        path = ::mkdtemp(t.data()) ? t : "";
    }
    ~ScratchDir() {
        std::error_code ec;
        if (!path.empty()) fs::remove_all(path, ec);
    }
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

template <typename T>
void writeWithOiio(const std::string &path, OIIO::ImageSpec spec, const std::vector<T> &pixels) {
    spec.attribute("oiio:UnassociatedAlpha", 1);  // the samples as given, alpha or not
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << path;
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(spec.format, pixels.data())) << out->geterror();
    ASSERT_TRUE(out->close());
}

// What OpenImageIO reads: names, the first channel's type, every channel in that type (float for
// half), as the reader before this one did; samples as stored (OpenImageIO would multiply a PNG's
// color by its alpha unless asked not to; visaudit's pictures have no alpha).
void expectSameAsOiio(const std::string &path) {
    SCOPED_TRACE(path);
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    ASSERT_TRUE(in) << OIIO::geterror();
    const OIIO::ImageSpec &spec = in->spec();
    OIIO::TypeDesc type = spec.channelformats.empty() ? spec.format : spec.channelformats[0];
    if (type == OIIO::TypeDesc::HALF) type = OIIO::TypeDesc::FLOAT;
    const size_t count = size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels);
    ImageData got;
    std::string err;
    ASSERT_TRUE(readImage(path, &got, &err)) << err;
    EXPECT_EQ(got.width, spec.width);
    EXPECT_EQ(got.height, spec.height);
    EXPECT_EQ(got.channelNames, spec.channelnames);
    EXPECT_EQ(got.pixelType, std::string(type.c_str()));
    auto compare = [&](const auto &mine) {
        using T = typename std::decay_t<decltype(mine)>::value_type;
        std::vector<T> theirs(count);
        ASSERT_TRUE(in->read_image(0, 0, 0, spec.nchannels, type, theirs.data())) << in->geterror();
        ASSERT_EQ(mine.size(), count);
        EXPECT_EQ(std::memcmp(mine.data(), theirs.data(), count * sizeof(T)), 0);
    };
    if (type == OIIO::TypeDesc::UINT8) compare(got.u8);
    else if (type == OIIO::TypeDesc::UINT16) compare(got.u16);
    else if (type == OIIO::TypeDesc::UINT32) compare(got.u32);
    else compare(got.f32);
}

}  // namespace

TEST(ImageRead, PngsAsOpenImageIOReadThem) {
    ScratchDir dir;
    const int W = 37, H = 23;  // odd sizes: no row happens to align
    for (int channels = 1; channels <= 4; ++channels) {
        const std::string base = dir.path + "/c" + std::to_string(channels);
        writeWithOiio(base + "-8.png", OIIO::ImageSpec(W, H, channels, OIIO::TypeDesc::UINT8),
                      samples<uint8_t>(size_t(W) * H * channels, 7 + channels));
        writeWithOiio(base + "-16.png", OIIO::ImageSpec(W, H, channels, OIIO::TypeDesc::UINT16),
                      samples<uint16_t>(size_t(W) * H * channels, 11 + channels));
        expectSameAsOiio(base + "-8.png");
        expectSameAsOiio(base + "-16.png");
    }
    // visaudit's own PNGs: a palette (few colors) and RGB (more than 256).
    std::vector<uint8_t> few(size_t(W) * H * 3), many = samples<uint8_t>(size_t(W) * H * 3, 3);
    for (size_t i = 0; i < few.size(); ++i) few[i] = uint8_t((i / 3 % 5) * 40 + i % 3);
    std::string err;
    ASSERT_TRUE(writePngRgb8(dir.path + "/palette.png", W, H, few.data(), &err)) << err;
    ASSERT_TRUE(writePngRgb8(dir.path + "/rgb.png", W, H, many.data(), &err)) << err;
    expectSameAsOiio(dir.path + "/palette.png");
    expectSameAsOiio(dir.path + "/rgb.png");
    ImageData im;
    ASSERT_TRUE(readImage(dir.path + "/palette.png", &im, &err)) << err;
    EXPECT_EQ(im.u8, few);  // the palette expanded to the pixels written
}

TEST(ImageRead, ExrsAsOpenImageIOReadThem) {
    ScratchDir dir;
    const int W = 29, H = 17;
    {
        OIIO::ImageSpec z(W, H, 1, OIIO::TypeDesc::FLOAT);
        z.channelnames = {"Z"};
        writeWithOiio(dir.path + "/z.exr", z, samples<float>(size_t(W) * H, 1));
        OIIO::ImageSpec id(W, H, 1, OIIO::TypeDesc::UINT32);
        id.channelnames = {"id"};
        writeWithOiio(dir.path + "/id.exr", id, samples<uint32_t>(size_t(W) * H, 2));
        writeWithOiio(dir.path + "/rgba-half.exr", OIIO::ImageSpec(W, H, 4, OIIO::TypeDesc::HALF),
                      samples<float>(size_t(W) * H * 4, 3));
        // Channels the file stores alphabetically; R, G, B, A come first when read.
        OIIO::ImageSpec mixed(W, H, 5, OIIO::TypeDesc::FLOAT);
        mixed.channelnames = {"R", "G", "B", "A", "Z"};
        mixed.x = 5, mixed.y = -3;  // a data window off the origin
        writeWithOiio(dir.path + "/mixed.exr", mixed, samples<float>(size_t(W) * H * 5, 4));
    }
    for (const char *name : {"z.exr", "id.exr", "rgba-half.exr", "mixed.exr"}) expectSameAsOiio(dir.path + "/" + name);
    ImageData im;
    std::string err;
    ASSERT_TRUE(readImage(dir.path + "/mixed.exr", &im, &err)) << err;
    EXPECT_EQ(im.channelNames, (std::vector<std::string>{"R", "G", "B", "A", "Z"}));
    EXPECT_EQ(im.width, W);
    EXPECT_EQ(im.height, H);
}

TEST(ImageRead, NotAnImageOrCutShortIsAMessage) {
    ScratchDir dir;
    std::string err;
    ImageData im;
    EXPECT_FALSE(readImage(dir.path + "/absent.png", &im, &err));
    EXPECT_NE(err.find("absent.png"), std::string::npos) << err;
    {
        std::ofstream(dir.path + "/text.png") << "not an image at all\n";
    }
    EXPECT_FALSE(readImage(dir.path + "/text.png", &im, &err));
    EXPECT_NE(err.find("neither a PNG nor an OpenEXR file"), std::string::npos) << err;
    // A PNG header claiming 60000 x 60000 pixels (and no data): refused before 3.6 GB are allocated.
    {
        auto be32 = [](std::string &s, uint32_t v) {
            for (int k = 3; k >= 0; --k) s += char(v >> (8 * k) & 0xFF);
        };
        std::string png("\x89PNG\r\n\x1a\n", 8), ihdr = "IHDR";
        be32(ihdr, 60000);
        be32(ihdr, 60000);
        ihdr += std::string("\x08\x00\x00\x00\x00", 5);  // 8-bit gray, no interlace
        be32(png, 13);
        png += ihdr;
        be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef *>(ihdr.data()), uInt(ihdr.size()))));
        const std::string idat("IDAT\x78\x01", 6);  // a zlib header only: the header is read up to here
        be32(png, 2);
        png += idat;
        be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef *>(idat.data()), uInt(idat.size()))));
        std::ofstream(dir.path + "/huge.png", std::ios::binary) << png;
        EXPECT_FALSE(readImage(dir.path + "/huge.png", &im, &err));
        EXPECT_NE(err.find("2^27 pixels"), std::string::npos) << err;
    }
    // Every prefix of a real PNG and EXR: refused with the file's name, never a crash.
    const int W = 40, H = 30;
    std::vector<uint8_t> rgb = samples<uint8_t>(size_t(W) * H * 3, 9);
    ASSERT_TRUE(writePngRgb8(dir.path + "/whole.png", W, H, rgb.data(), &err)) << err;
    OIIO::ImageSpec z(W, H, 1, OIIO::TypeDesc::FLOAT);
    z.channelnames = {"Z"};
    writeWithOiio(dir.path + "/whole.exr", z, samples<float>(size_t(W) * H, 5));
    for (const char *name : {"whole.png", "whole.exr"}) {
        std::ifstream f(dir.path + "/" + name, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        ASSERT_GT(bytes.size(), 100u);
        for (size_t cut = 0; cut < bytes.size(); cut += 1 + cut / 8) {
            const std::string path = dir.path + "/cut-" + std::to_string(cut) + "-" + name;
            std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(cut));
            EXPECT_FALSE(readImage(path, &im, &err)) << path;
            EXPECT_NE(err.find(path), std::string::npos) << err;
        }
    }
}
