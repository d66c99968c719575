// Zip archives (.pk3) through analysis/load/zip.h: list the members, read each of the first eight (the
// size limit lowered to 16 MB for the fuzzer's memory limit), then look up a missing member, which
// walks the names for the message's suggestions.
#include "analysis/load/zip.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput("input.pk3", data, size);
    std::vector<std::string> names;
    std::string err;
    const bool ok = va::listZipMembers(path, &names, &err);
    va::fuzz::checkResult(ok, err, path);
    if (!ok) return 0;
    std::vector<uint8_t> bytes;
    for (size_t i = 0; i < names.size() && i < 8; ++i) {
        err.clear();
        va::fuzz::checkResult(va::readZipMember(path, names[i], 16u << 20, &bytes, &err), err, path);
    }
    err.clear();
    va::fuzz::checkResult(va::readZipMember(path, "maps/missing.bsp", 16u << 20, &bytes, &err), err, path);
    return 0;
}
