// Resource limits (limits.h; docs/limits.md).
#include "common/limits.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace va {

uint64_t defaultMaxMemory() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
    uint64_t avail = pages > 0 && pageSize > 0 ? uint64_t(pages) * uint64_t(pageSize) : 0;
    // cgroup v2: "max" or a byte count. A container's limit is lower than the host's RAM, and
    // exceeding it gets the process killed without a message.
    std::ifstream f("/sys/fs/cgroup/memory.max");
    std::string v;
    if (f >> v && !v.empty() && std::isdigit((unsigned char)v[0])) {
        const uint64_t cg = std::strtoull(v.c_str(), nullptr, 10);
        if (cg > 0 && (avail == 0 || cg < avail)) avail = cg;
    }
    return avail / 4 * 3;
}

bool parseByteSize(const std::string &text, uint64_t *bytes, std::string *err) {
    auto bad = [&] {
        *err = "'" + text + "' is not a size; give bytes or a number with K, M, G or T (binary units), e.g. 8G or 1.5G";
        return false;
    };
    const char *s = text.c_str();
    char *end = nullptr;
    const double x = std::strtod(s, &end);
    if (end == s || !std::isfinite(x) || x < 0) return bad();
    std::string unit(end);
    for (char &c : unit) c = char(std::toupper((unsigned char)c));
    if (unit.size() >= 2 && unit.back() == 'B') unit.pop_back();    // "GB", "GiB" -> "G", "GI"
    if (unit.size() >= 2 && unit.back() == 'I') unit.pop_back();
    const std::string units = "KMGT";
    double scale = 1;
    if (!unit.empty()) {
        const size_t k = units.find(unit);
        if (unit.size() != 1 || k == std::string::npos) return bad();
        scale = std::ldexp(1.0, 10 * int(k + 1));
    }
    const double b = std::floor(x * scale);
    if (b >= 0x1p64) return bad();
    *bytes = uint64_t(b);
    return true;
}

std::string formatBytes(uint64_t bytes) {
    const char *units[] = {"KiB", "MiB", "GiB", "TiB", "PiB"};
    if (bytes < 1024) return std::to_string(bytes) + " B";
    double x = double(bytes);
    int k = -1;
    while (x >= 1024 && k < 4) x /= 1024, ++k;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f %s", x, units[k]);
    return buf;
}

bool checkTriangleLimit(uint64_t need, uint64_t limit, const std::string &what, std::string *err) {
    if (need <= limit) return true;
    *err = what + " needs " + std::to_string(need) + " triangles, more than the limit of " + std::to_string(limit) +
           "; raise it with --max-triangles " + std::to_string(need) + " if the machine has the memory (about " +
           formatBytes(need * kBytesPerTriangle) + "), or the file is damaged";
    return false;
}

}  // namespace va
