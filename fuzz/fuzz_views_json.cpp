// Views files ({ "views": [ ... ] }) through loadViewsFile, with a z-up scene's default.
#include "analysis/load/load.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput("input.views.json", data, size);
    std::vector<va::ViewSpec> views;
    std::string err;
    const bool ok = va::loadViewsFile(path, 'z', &views, &err);
    va::fuzz::checkResult(ok, err, path);
    return 0;
}
