// Numbers as report text (reports/text_format.h).
#include "reports/text_format.h"

#include <cmath>
#include <cstdio>

namespace va {

std::string fmtCount(double v) {
    if (!std::isfinite(v)) return "—";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.0f", std::fabs(v));
    std::string digits = buf, o;
    for (size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) o += ',';
        o += digits[i];
    }
    return (v < 0 && o != "0" ? "-" : "") + o;
}

std::string fmtReal(double v) {
    if (!std::isfinite(v)) return "—";
    if (v == 0) return "0";
    if (std::fabs(v) >= 1e4 && std::fabs(v) < 1e15) return fmtCount(std::round(v));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

std::string fmtMs(std::optional<double> ms) { return ms ? fmtReal(*ms) + " ms" : "—"; }

std::string pct(double part, double whole) {
    if (!(whole > 0)) return "—";
    char buf[32];
    const double p = 100.0 * part / whole;
    // Small shares keep two significant digits, shares just short of 100% two decimals, so that
    // neither rounds to 0.0% or 100.0%.
    const char *f = p != 0 && p < 0.1 ? "%.2g%%" : (p > 99.9 && part < whole) ? "%.2f%%" : "%.1f%%";
    std::snprintf(buf, sizeof buf, f, p);
    return buf;
}

std::string plural(double n, const char *one, const char *many) { return fmtCount(n) + " " + (n == 1 ? one : many); }

}  // namespace va
