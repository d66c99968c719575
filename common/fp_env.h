// The floating-point environment the analysis computes in: IEEE 754's defaults (round to nearest,
// subnormals kept: no flush-to-zero, no denormals-are-zero), on every thread that takes a part of
// it. The project's bit-for-bit arguments ("the same IEEE operations, so the same bits") assume them.
//
// Why it must be set, not assumed: TBB runs each task under the SSE and x87 control settings its
// task_group_context captured, and a context without its own takes its parent's, up to the default
// context, which captures the settings of the thread that first used TBB in the process. Embree's
// scene build uses TBB with flush-to-zero and denormals-are-zero on, so when Embree was the first
// user every view ran with them (the painter's overlap counts of oa_thor moved when the BSP tree's
// build, until then the first user, moved to a thread of its own). runWithIeeeFp gives the work a
// context of its own that carries the defaults to every thread, nested parallel loops included.
#pragma once

#include <utility>

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

#include <tbb/task_group.h>

namespace va {

// MXCSR with every exception masked, round to nearest, flush-to-zero and denormals-are-zero off.
constexpr unsigned kIeeeMxcsr = 0x1F80;

// This thread's SSE control set to IEEE defaults while in scope (its status flags kept), then put back.
class IeeeFpScope {
public:
#if defined(__x86_64__) || defined(__i386__)
    IeeeFpScope() : saved_(_mm_getcsr()) { _mm_setcsr(kIeeeMxcsr | (saved_ & 0x3Fu)); }
    ~IeeeFpScope() { _mm_setcsr(saved_); }
#endif
    IeeeFpScope(const IeeeFpScope &) = delete;
    IeeeFpScope &operator=(const IeeeFpScope &) = delete;

private:
#if defined(__x86_64__) || defined(__i386__)
    unsigned saved_;
#endif
};

// f() on this thread under IEEE defaults, as a task of a context that captured them: TBB loops
// inside f (and inside those) run their tasks under the same settings on every thread.
template <class F>
void runWithIeeeFp(F &&f) {
    const IeeeFpScope ieee;
    tbb::task_group_context context(tbb::task_group_context::bound, tbb::task_group_context::fp_settings);
    tbb::task_group group(context);
    group.run_and_wait(std::forward<F>(f));
}

}  // namespace va
