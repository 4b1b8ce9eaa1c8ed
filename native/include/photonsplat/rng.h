// Counter-based random numbers: every stream is keyed by (seed, domain, index), so a photon or a pixel draws
// the same numbers whichever thread traces it and in whatever order. That is what makes images bit-identical
// for any thread count.
#pragma once
#include <cstdint>

namespace ps {

// Which part of the renderer a stream belongs to, so pixel 7 and photon 7 never share numbers.
enum class RngDomain : uint64_t {
    camera = 1,
    direct_light = 2,
    photon = 3,
    light_choice = 4,
    emission_guide = 5,
    kernel_probe = 7,       // automatic radius: the rotation of a seen point's probe pattern (kernel_radius.cpp)
    kernel_coverage = 8,    // boundary correction: the rotation of a view sample's probe pattern (kernel_coverage.cpp)
    sample_sequence = 9,    // a pixel's scramble of its low-discrepancy points across iterations (sample_sequence.h)
    reference_path = 16,    // reference renderer: one camera path, keyed by pass × pixels + pixel
    reference_photon = 17,  // reference renderer: one caustic photon, keyed by pass × photons + photon
    glass_walk = 18,        // the microsurface walks that tabulate Multiscatter GGX glass (glass_multiscatter.cpp)
    glass_light_value = 19, // Cycles' walk that evaluates that glass towards a light sample (glass_multiscatter.cpp)
    dropped_direct = 20,    // direct light through the parts the Caustics output takes whole (direct_light.cpp)
};

// PCG32 (O'Neill 2014), with state and stream derived from the key by SplitMix64.
class Rng {
public:
    Rng(uint64_t seed, RngDomain domain, uint64_t index) {
        uint64_t s = mix(seed ^ mix(static_cast<uint64_t>(domain) * 0x9E3779B97F4A7C15ull + index));
        inc_ = (mix(s + 0x632BE59BD9B4E019ull) << 1u) | 1u;
        state_ = 0;
        next_u32();
        state_ += s;
        next_u32();
    }

    uint32_t next_u32() {
        uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }

    // Uniform in [0, 1): 24 random bits, so the result is exactly representable and never 1.
    float uniform() { return static_cast<float>(next_u32() >> 8) * (1.0f / 16777216.0f); }

private:
    static uint64_t mix(uint64_t z) {
        z += 0x9E3779B97F4A7C15ull;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    uint64_t state_ = 0;
    uint64_t inc_ = 1;
};

}  // namespace ps
