// A vector whose resize leaves new elements default-initialized: for trivial types, uninitialized.
//
// std::vector value-initializes what resize adds, so a fresh 1080p id buffer (8 MB) is cleared in
// one pass over memory before anything writes it. A buffer that is filled piece by piece anyway
// (the ordering audit's ids are cleared a band of rows at a time, in the core's cache, just before
// that band is drawn) skips that pass with this allocator. Reading an element before writing it is
// as undefined as with new T[n].
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace va {

template <class T, class A = std::allocator<T>>
class DefaultInitAllocator : public A {
    using Traits = std::allocator_traits<A>;

  public:
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
    };
    using A::A;

    template <class U>
    void construct(U *p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void *>(p)) U;
    }
    template <class U, class... Args>
    void construct(U *p, Args &&...args) {
        Traits::construct(static_cast<A &>(*this), p, std::forward<Args>(args)...);
    }
};

template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace va
