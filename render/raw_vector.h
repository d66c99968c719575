// Vectors whose resize does not clear what it adds.
//
// std::vector value-initializes what resize adds, so a fresh 1080p buffer (8 MB) is cleared in one
// pass over memory before anything writes it. SkipInitAllocator's construct() with no arguments
// does less:
//  - SkipInit::defaultInit: default-initializes (for trivial types nothing; a type's default member
//    initializers still run). common/uninit_vector.h's UninitVector: buffers filled piece by piece
//    anyway (the ordering audit's ids, cleared a band of rows at a time just before the band is
//    drawn).
//  - SkipInit::everything: writes nothing at all, for types whose objects may hold any bytes
//    (trivially copyable and destructible), even where default-initialization would set members
//    (DepthPlane's `valid = false`). RawVector: a writer that resizes first and then stores every
//    added element in place, with no staging copy (the clip stage's output, raster.h:
//    ScreenTriangles; clip_avx2.cpp writes four accepted triangles at a time into it).
// Reading an added element before it is written is as undefined as with new T[n] (default) or
// reads unspecified bytes (everything).
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace va {

enum class SkipInit { defaultInit, everything };

template <class T, SkipInit kSkip, class A = std::allocator<T>>
class SkipInitAllocator : public A {
    using Traits = std::allocator_traits<A>;

  public:
    template <class U>
    struct rebind {
        using other = SkipInitAllocator<U, kSkip, typename Traits::template rebind_alloc<U>>;
    };
    using A::A;

    template <class U>
    void construct(U *p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        if constexpr (kSkip == SkipInit::everything)
            static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>,
                          "SkipInit::everything leaves objects unwritten: only for types that may hold any bytes");
        else
            ::new (static_cast<void *>(p)) U;
    }
    template <class U, class... Args>
    void construct(U *p, Args &&...args) {
        Traits::construct(static_cast<A &>(*this), p, std::forward<Args>(args)...);
    }
};

template <class T>
using RawVector = std::vector<T, SkipInitAllocator<T, SkipInit::everything>>;

}  // namespace va
