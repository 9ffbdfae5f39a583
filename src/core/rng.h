// Deterministic random numbers: a PCG32 stream per (seed, pixel, sample), so that an image depends only on
// the seed and never on the thread count or the tile order.
#pragma once

#include <cstdint>

#include "core/platform.h"
#include "core/vec.h"

namespace npt {

// 64-bit finaliser of MurmurHash3: spreads (seed, pixel, sample) into independent stream states.
NPT_HD NPT_INLINE uint64_t mix64(uint64_t k) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ULL;
    k ^= k >> 33;
    return k;
}

class Pcg32 {
  public:
    Pcg32() = default;  // implicitly __host__ __device__ under nvcc
    NPT_HD Pcg32(uint64_t seed, uint64_t stream) { set_sequence(seed, stream); }

    // One stream per pixel and sample index; `seed` is the user's --seed.
    NPT_HD static Pcg32 for_pixel(uint64_t seed, uint32_t px, uint32_t py, uint32_t sample) {
        uint64_t pixel = (uint64_t(py) << 32) | px;
        return Pcg32(mix64(seed ^ mix64(pixel)),
                     mix64(pixel + 0x9e3779b97f4a7c15ULL * (uint64_t(sample) + 1)));
    }

    NPT_HD void set_sequence(uint64_t seed, uint64_t stream) {
        m_state = 0;
        m_inc = (stream << 1u) | 1u;
        next_u32();
        m_state += seed;
        next_u32();
    }

    NPT_HD uint32_t next_u32() {
        uint64_t old = m_state;
        m_state = old * 0x5851f42d4c957f2dULL + m_inc;
        uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }

    // Uniform in [0, 1): 24 random mantissa bits, never 1.
    NPT_HD float next_float() { return float(next_u32() >> 8) * 0x1p-24f; }
    NPT_HD float next_1d() { return next_float(); }  // the sampler interface the integrator uses
    NPT_HD Vec2 next_2d() {
        float a = next_float();
        return {a, next_float()};
    }

  private:
    uint64_t m_state = 0x853c49e6748fea9bULL;
    uint64_t m_inc = 0xda3e39cb94b95bdbULL;
};

}  // namespace npt
