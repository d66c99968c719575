// splitmix64: a fixed, portable random sequence for everything visaudit samples (walk views, the
// PVS audit's eye points and ray rotations). std::uniform_*_distribution is implementation-defined,
// so it is never used: the same seed gives the same numbers with every standard library.
#pragma once

#include <cstdint>

namespace va {

struct SplitMix64 {
    uint64_t s;
    uint64_t next() {
        uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    // Uniform in [0, n): the high 64 bits of a 128-bit product (Lemire), bias below 2^-64 * n.
    uint64_t below(uint64_t n) { return uint64_t((unsigned __int128)next() * n >> 64); }
    double unit() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

}  // namespace va
