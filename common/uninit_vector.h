// A vector whose resize leaves new elements default-initialized: for trivial types, uninitialized.
//
// std::vector value-initializes what resize adds, so a fresh 1080p id buffer (8 MB) is cleared in
// one pass over memory before anything writes it. A buffer that is filled piece by piece anyway
// (the ordering audit's ids are cleared a band of rows at a time, in the core's cache, just before
// that band is drawn) skips that pass with this vector. Reading an element before writing it is
// as undefined as with new T[n]. The allocator is render/raw_vector.h's, which RawVector (nothing
// written at all, for the clip stage's output) shares.
#pragma once

#include <vector>

#include "render/raw_vector.h"

namespace va {

template <class T>
using UninitVector = std::vector<T, SkipInitAllocator<T, SkipInit::defaultInit>>;

}  // namespace va
