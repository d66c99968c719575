// Numbers as the report's prose and tables write them (report.html, the findings): plain text, no
// markup, deterministic (printf formats, no locale).
#pragma once

#include <optional>
#include <string>

namespace va {

// A whole number with thousands separators: 462881 -> "462,881"; not finite: "—".
std::string fmtCount(double v);
// A real number, 4 significant digits (large values as counts): 1.27776 -> "1.278".
std::string fmtReal(double v);
// "12.5 ms", or "—" when absent.
std::string fmtMs(std::optional<double> ms);
// part / whole as a percentage ("12.3%"); small shares keep two significant digits and shares just
// short of 100% two decimals, so neither rounds to 0.0% or 100.0%. "—" when whole is not positive.
std::string pct(double part, double whole);
// "1 view", "3 views" (the count with separators).
std::string plural(double n, const char *one, const char *many);

}  // namespace va
