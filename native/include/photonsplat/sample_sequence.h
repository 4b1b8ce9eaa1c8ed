// Low-discrepancy points per view sample, continued across the iterations of a progressive render: iteration i takes
// points i·n … i·n + n − 1. Cycles draws a pixel's samples from one such sequence, so its error falls faster than
// 1/N where the integrand is smooth (the sky over a floor); independent random numbers per iteration do not.
// Used for a programmed world's direct light, and for where the reference renderer's passes fall in each pixel.
//
// Dimensions 1 and 2 are Sobol's (0,2)-sequence (the radical inverse in base 2 and Sobol's second dimension),
// Owen-scrambled per pixel and stream by hashing (Burley 2020, "Practical Hash-based Owen Scrambling": a
// Laine–Karras permutation of the bit-reversed value), and each stream takes the points in its own shuffled
// order (the same scrambling of the index). Scrambling the values alone (an XOR) would leave two streams the
// same sequence in a fixed relation: where a light sample goes would decide where its BSDF sample goes.
// Dimension 3 is the radical inverse in base 3 of the shuffled index, rotated. The scrambles come from the
// render's seed and the pixel, never from the iteration, so the iterations continue one sequence.
#pragma once
#include <cstdint>

#include "photonsplat/rng.h"

namespace ps {

class SampleSequence {
public:
    static constexpr uint64_t kLightStream = 0, kBsdfStream = 1, kPixelStream = 2;

    // `key`: the view sample (pixel and branch), or the pixel; `stream`: which use of the sequence, each scrambled
    // apart (kLightStream: light samples, kBsdfStream: BSDF samples, kPixelStream: positions in the pixel).
    SampleSequence(uint64_t seed, uint64_t key, uint64_t stream) {
        Rng rng(seed ^ (stream * 0xA24BAED4963EE407ull), RngDomain::sample_sequence, key);
        shuffle_ = rng.next_u32();
        scramble1_ = rng.next_u32();
        scramble2_ = rng.next_u32();
        shift3_ = rng.uniform();
    }

    // Where pass `index` of a render of `seed` places its camera ray in `pixel` (x, y in [0, 1)): the pixel's own
    // sequence, as Cycles places a pixel's samples (the reference renderer and progressive passes).
    static void pixel_point(uint64_t seed, uint64_t pixel, uint32_t index, float& x, float& y) {
        float unused = 0.0f;
        SampleSequence(seed, pixel, kPixelStream).point(index, x, y, unused);
    }

    // The index-th point, each coordinate in [0, 1).
    void point(uint32_t index, float& u1, float& u2, float& u3) const {
        const uint32_t i = owen(index, shuffle_);
        u1 = to_unit(owen(reverse_bits(i), scramble1_));
        u2 = to_unit(owen(sobol2(i), scramble2_));
        float r = radical_inverse3(i) + shift3_;
        u3 = r >= 1.0f ? r - 1.0f : r;
        if (!(u3 < 1.0f)) u3 = 0.0f;
    }

private:
    uint32_t shuffle_, scramble1_, scramble2_;

    // Nested uniform scrambling of x's bits (each bit flipped by a hash of the bits above it): a Laine–Karras
    // permutation, which flips by the bits below, applied to the bit-reversed value.
    static uint32_t owen(uint32_t x, uint32_t seed) {
        x = reverse_bits(x);
        x ^= x * 0x3d20adeau;
        x += seed;
        x *= (seed >> 16) | 1u;
        x ^= x * 0x05526c56u;
        x ^= x * 0x53a22864u;
        return reverse_bits(x);
    }
    float shift3_;

    static float to_unit(uint32_t bits) { return static_cast<float>(bits >> 8) * (1.0f / 16777216.0f); }
    static uint32_t reverse_bits(uint32_t v) {
        v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
        v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
        v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
        v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
        return (v >> 16) | (v << 16);
    }
    // Sobol's second dimension: the generator matrix is Pascal's triangle mod 2 (direction numbers v_k = v_{k-1}
    // xor v_{k-1} >> 1, from the top bit).
    static uint32_t sobol2(uint32_t index) {
        uint32_t r = 0;
        for (uint32_t v = 1u << 31; index; index >>= 1, v ^= v >> 1)
            if (index & 1u) r ^= v;
        return r;
    }
    static float radical_inverse3(uint32_t index) {
        double r = 0.0, f = 1.0 / 3.0;
        for (; index; index /= 3, f /= 3.0) r += f * double(index % 3);
        return static_cast<float>(r);
    }
};

}  // namespace ps
