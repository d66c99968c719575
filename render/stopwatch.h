// The one clock behind every timing field of a report (stage `ms`, audit times, build times, the
// output phase). A timing is the only part of a report that differs between two runs of the same
// input; with the environment variable VISAUDIT_FIXED_TIMINGS=1 every interval measured here reads
// exactly 0 ms, so that whole report folders (report.json, report.html, JUnit) can be compared byte
// for byte -- what tests/test_golden_outputs.cpp does to prove a refactor changed no output.
// Progress lines and benchmarks use the real clock directly; they are not report fields.
#pragma once

#include <chrono>
#include <cstdlib>
#include <cstring>

namespace va {

class Stopwatch {
  public:
    using Clock = std::chrono::steady_clock;
    Stopwatch() : t0_(Clock::now()) {}
    // Milliseconds since construction or the last restart (0 with VISAUDIT_FIXED_TIMINGS=1).
    double ms() const {
        if (fixedTimings()) return 0.0;
        return std::chrono::duration<double, std::milli>(Clock::now() - t0_).count();
    }
    void restart() { t0_ = Clock::now(); }

    // True when VISAUDIT_FIXED_TIMINGS is set to a value other than "0" (read once).
    static bool fixedTimings() {
        static const bool fixed = [] {
            const char *v = std::getenv("VISAUDIT_FIXED_TIMINGS");
            return v && *v && std::strcmp(v, "0") != 0;
        }();
        return fixed;
    }

  private:
    Clock::time_point t0_;
};

}  // namespace va
