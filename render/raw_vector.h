// A vector whose resize writes nothing into the elements it adds.
//
// std::vector value-initializes what resize adds, and default-initialization (common/
// uninit_vector.h) still runs a type's default member initializers (DepthPlane's `valid = false`).
// NoInitAllocator's construct() with no arguments writes nothing at all, for types whose objects
// may hold any bytes (trivially copyable and destructible). It is for a writer that resizes first
// and then stores every added element in place, with no staging copy: the clip stage's output
// (raster.h, ScreenTriangles; clip_avx2.cpp writes four accepted triangles at a time into it).
// Reading an added element before it is written reads unspecified bytes.
#pragma once

#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace va {

template <class T, class A = std::allocator<T>>
class NoInitAllocator : public A {
    using Traits = std::allocator_traits<A>;

  public:
    template <class U>
    struct rebind {
        using other = NoInitAllocator<U, typename Traits::template rebind_alloc<U>>;
    };
    using A::A;

    template <class U>
    void construct(U *) noexcept {
        static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>,
                      "NoInitAllocator leaves objects unwritten: only for types that may hold any bytes");
    }
    template <class U, class... Args>
    void construct(U *p, Args &&...args) {
        Traits::construct(static_cast<A &>(*this), p, std::forward<Args>(args)...);
    }
};

template <class T>
using RawVector = std::vector<T, NoInitAllocator<T>>;

}  // namespace va
