// Images read back (readImage, reports/image_read.cpp: PNG through libpng, EXR through OpenEXR):
// grading reads students' files with it. The contract as the loaders' (fuzz_util.h), and a read
// image's pixel vector holds width x height x channels samples of its type.
#include <cstdint>
#include <cstdlib>

#include "fuzz/fuzz_util.h"
#include "reports/report.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput("input.image", data, size);
    va::ImageData im;
    std::string err;
    const bool ok = va::readImage(path, &im, &err);
    va::fuzz::checkResult(ok, err, path);
    if (ok) {
        const size_t n = size_t(im.width) * size_t(im.height) * size_t(im.channels());
        const size_t held = im.pixelType == "float" ? im.f32.size()
                            : im.pixelType == "uint" ? im.u32.size()
                            : im.pixelType == "uint16" ? im.u16.size()
                            : im.pixelType == "uint8" ? im.u8.size()
                                                      : SIZE_MAX;
        if (im.width <= 0 || im.height <= 0 || held != n) {
            std::fprintf(stderr, "fuzz: %dx%d x %d channels of '%s', %zu samples held\n", im.width, im.height,
                         im.channels(), im.pixelType.c_str(), held);
            std::abort();
        }
    }
    return 0;
}
