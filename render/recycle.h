// Storage handed from one view to the next.
//
// A 1080p view fills tens of megabytes of fresh buffers (the z-buffer's five per-pixel arrays, the
// clip's screen triangles, the reference's fragments); freed at the end of a view they go back to
// the kernel (glibc maps allocations this large on their own), and the next view faults every page
// in again and has it cleared: on the 1M-triangle benchmark scene that was a fifth of the z-buffer's
// time and of the clip's. A Recycler keeps what a finished view gives back, emptied but with its
// memory, for the next one to take. It holds at most as many as were ever in use at once (one per
// view in flight), so the peak memory does not change; taking from an empty one gives a fresh T.
#pragma once

#include <mutex>
#include <utility>
#include <vector>

namespace va {

template <class T>
class Recycler {
  public:
    T take() {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (kept_.empty()) return T{};
        T t = std::move(kept_.back());
        kept_.pop_back();
        return t;
    }
    void give(T &&t) {
        const std::lock_guard<std::mutex> lock(mutex_);
        kept_.push_back(std::move(t));
    }

  private:
    std::mutex mutex_;
    std::vector<T> kept_;
};

// The process's one Recycler of T, never destroyed: a view still running while the process exits
// may give its storage back after static destructors have run.
template <class T>
Recycler<T> &recyclerOf() {
    static Recycler<T> &r = *new Recycler<T>;
    return r;
}

}  // namespace va
