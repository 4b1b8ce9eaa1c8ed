// Cycles 3.4's noise primitives (noise.h says what and why).
#include "nodes/noise.h"

#include <cmath>
#include <cstring>

// Rounding. The goldens are Blender 3.4's x86 AVX2 Cycles kernel, and at high detail the finest octaves sample
// the lattice at 2^15 times the coordinate, where one ulp anywhere upstream shows (up to 5e-3 in Fac). So this
// file does that kernel's arithmetic, not merely its formulas: the multiply-adds it fuses (its SIMD madd() is an
// FMA on AVX2, and its compiler contracts some scalar steps) are written as std::fma, its interpolation order is
// kept, and nothing else may be fused. Our compiler must not fuse on its own (clang does when it folds constants,
// even for targets without FMA; GCC on FMA targets): hence the pragmas. Each fused step below was chosen because
// it brings the renders' values closer (test_texture_nodes.cpp measures it).
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace ps {
namespace noise {

float mix(float a, float b, float t) { return a + t * (b - a); }

// --- hashes ------------------------------------------------------------------------------------------------------

namespace {

constexpr uint32_t rotl(uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }

// lookup3's mix() and final(), on the three-word state, laid out as in lookup3.c.
// clang-format off
void lookup3_mix(uint32_t& a, uint32_t& b, uint32_t& c) {
    a -= c; a ^= rotl(c, 4);  c += b;
    b -= a; b ^= rotl(a, 6);  a += c;
    c -= b; c ^= rotl(b, 8);  b += a;
    a -= c; a ^= rotl(c, 16); c += b;
    b -= a; b ^= rotl(a, 19); a += c;
    c -= b; c ^= rotl(b, 4);  b += a;
}

void lookup3_final(uint32_t& a, uint32_t& b, uint32_t& c) {
    c ^= b; c -= rotl(b, 14);
    a ^= c; a -= rotl(c, 11);
    b ^= a; b -= rotl(a, 25);
    c ^= b; c -= rotl(b, 16);
    a ^= c; a -= rotl(c, 4);
    b ^= a; b -= rotl(a, 14);
    c ^= b; c -= rotl(b, 24);
}
// clang-format on

// lookup3's initial value for a key of `words` 32-bit words and seed 13, as Cycles seeds it.
constexpr uint32_t lookup3_seed(uint32_t words) { return 0xdeadbeefu + (words << 2) + 13u; }

// [0, 2^32 − 1] → [0, 1], both ends included.
float uint_to_unit_float(uint32_t n) { return static_cast<float>(n) * (1.0f / static_cast<float>(0xFFFFFFFFu)); }

uint32_t bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

}  // namespace

uint32_t hash_uint(uint32_t kx) {
    uint32_t a, b, c;
    a = b = c = lookup3_seed(1);
    a += kx;
    lookup3_final(a, b, c);
    return c;
}

uint32_t hash_uint2(uint32_t kx, uint32_t ky) {
    uint32_t a, b, c;
    a = b = c = lookup3_seed(2);
    b += ky;
    a += kx;
    lookup3_final(a, b, c);
    return c;
}

uint32_t hash_uint3(uint32_t kx, uint32_t ky, uint32_t kz) {
    uint32_t a, b, c;
    a = b = c = lookup3_seed(3);
    c += kz;
    b += ky;
    a += kx;
    lookup3_final(a, b, c);
    return c;
}

uint32_t hash_uint4(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw) {
    // Four words overflow lookup3's three-word state: the first three are mixed in, then the fourth.
    uint32_t a, b, c;
    a = b = c = lookup3_seed(4);
    a += kx;
    b += ky;
    c += kz;
    lookup3_mix(a, b, c);
    a += kw;
    lookup3_final(a, b, c);
    return c;
}

float hash_uint_to_float(uint32_t kx) { return uint_to_unit_float(hash_uint(kx)); }
float hash_uint2_to_float(uint32_t kx, uint32_t ky) { return uint_to_unit_float(hash_uint2(kx, ky)); }
float hash_uint3_to_float(uint32_t kx, uint32_t ky, uint32_t kz) {
    return uint_to_unit_float(hash_uint3(kx, ky, kz));
}
float hash_uint4_to_float(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw) {
    return uint_to_unit_float(hash_uint4(kx, ky, kz, kw));
}

float hash_float_to_float(float k) { return hash_uint_to_float(bits(k)); }
float hash_vec2_to_float(const glm::vec2& k) { return hash_uint2_to_float(bits(k.x), bits(k.y)); }
float hash_vec3_to_float(const glm::vec3& k) { return hash_uint3_to_float(bits(k.x), bits(k.y), bits(k.z)); }
float hash_vec4_to_float(const glm::vec4& k) {
    return hash_uint4_to_float(bits(k.x), bits(k.y), bits(k.z), bits(k.w));
}

// The further components hash the key with a constant appended or with its components rotated: Cycles' choices,
// which fix which values each cell gets.
glm::vec2 hash_vec2_to_vec2(const glm::vec2& k) {
    return {hash_vec2_to_float(k), hash_vec3_to_float(glm::vec3(k.x, k.y, 1.0f))};
}

glm::vec3 hash_vec3_to_vec3(const glm::vec3& k) {
    return {hash_vec3_to_float(k), hash_vec4_to_float(glm::vec4(k.x, k.y, k.z, 1.0f)),
            hash_vec4_to_float(glm::vec4(k.x, k.y, k.z, 2.0f))};
}

glm::vec4 hash_vec4_to_vec4(const glm::vec4& k) {
    return {hash_vec4_to_float(k), hash_vec4_to_float(glm::vec4(k.w, k.x, k.y, k.z)),
            hash_vec4_to_float(glm::vec4(k.z, k.w, k.x, k.y)), hash_vec4_to_float(glm::vec4(k.y, k.z, k.w, k.x))};
}

glm::vec3 hash_float_to_color(float k) {
    return {hash_float_to_float(k), hash_vec2_to_float(glm::vec2(k, 1.0f)), hash_vec2_to_float(glm::vec2(k, 2.0f))};
}

glm::vec3 hash_vec2_to_color(const glm::vec2& k) {
    return {hash_vec2_to_float(k), hash_vec3_to_float(glm::vec3(k.x, k.y, 1.0f)),
            hash_vec3_to_float(glm::vec3(k.x, k.y, 2.0f))};
}

glm::vec3 hash_vec4_to_color(const glm::vec4& k) {
    return {hash_vec4_to_float(k), hash_vec4_to_float(glm::vec4(k.z, k.x, k.w, k.y)),
            hash_vec4_to_float(glm::vec4(k.w, k.z, k.y, k.x))};
}

// --- Perlin noise -------------------------------------------------------------------------------------------------

namespace {

// Perlin's quintic fade 6t^5 - 15t^4 + 10t^3 (C2 across lattice cells), in Cycles' two roundings: its scalar 1D
// code (the polynomial contracted by its compiler) and its SIMD 2-4D code (madd() twice, then (t t)(t b)).
float fade_scalar(float t) { return t * t * t * std::fma(t, std::fma(t, 6.0f, -15.0f), 10.0f); }
float fade_simd(float t) { return (t * t) * (t * std::fma(t, std::fma(t, 6.0f, -15.0f), 10.0f)); }
// Cycles' SIMD mix(): madd(t, b, (1 - t) a).
float mix_simd(float a, float b, float t) { return std::fma(t, b, (1.0f - t) * a); }

float negate_if(float v, uint32_t condition) { return condition ? -v : v; }

// The gradients: Cycles' (from OSL) choice per dimension, picked by the corner's hash; each returns the dot of
// the gradient with the offset from the corner.
float grad(uint32_t hash, const float* q, int n) {
    const float x = q[0];
    switch (n) {
        case 1: {
            // 1D: a slope of ±1..8
            const uint32_t h = hash & 15u;
            const float g = static_cast<float>(1u + (h & 7u));
            return negate_if(g, h & 8u) * x;
        }
        case 2: {
            const uint32_t h = hash & 7u;
            const float y = q[1];
            const float u = h < 4 ? x : y;
            const float v = 2.0f * (h < 4 ? y : x);
            return negate_if(u, h & 1u) + negate_if(v, h & 2u);
        }
        case 3: {
            // the 12 cube-edge directions (four repeated to fill 16)
            const uint32_t h = hash & 15u;
            const float y = q[1], z = q[2];
            const float u = h < 8 ? x : y;
            const float vt = (h == 12 || h == 14) ? x : z;
            const float v = h < 4 ? y : vt;
            return negate_if(u, h & 1u) + negate_if(v, h & 2u);
        }
        default: {
            const uint32_t h = hash & 31u;
            const float y = q[1], z = q[2], w = q[3];
            const float u = h < 24 ? x : y;
            const float v = h < 16 ? y : z;
            const float s = h < 8 ? z : w;
            return negate_if(u, h & 1u) + negate_if(v, h & 2u) + negate_if(s, h & 4u);
        }
    }
}

uint32_t hash_cell(const uint32_t* k, int n) {
    switch (n) {
        case 1: return hash_uint(k[0]);
        case 2: return hash_uint2(k[0], k[1]);
        case 3: return hash_uint3(k[0], k[1], k[2]);
        default: return hash_uint4(k[0], k[1], k[2], k[3]);
    }
}

// Gradient noise in N dimensions: the gradients of the cell's 2^N corners (corner index bit d: the upper side
// along axis d), blended with the faded fractions.
template <int N>
float perlin_n(const float* p) {
    uint32_t cell[N];
    float frac[N], t[N];
    for (int d = 0; d < N; ++d) {
        const float fl = std::floor(p[d]);
        // Unsigned so that cell + 1 wraps (int overflow would be undefined) as Cycles' int arithmetic does.
        cell[d] = static_cast<uint32_t>(float_to_int(fl));
        frac[d] = p[d] - fl;
        t[d] = N == 1 ? fade_scalar(frac[d]) : fade_simd(frac[d]);
    }
    float corner[1 << N];
    for (int c = 0; c < (1 << N); ++c) {
        uint32_t k[N];
        float q[N];
        for (int d = 0; d < N; ++d) {
            const bool upper = (c >> d) & 1;
            k[d] = cell[d] + (upper ? 1u : 0u);
            q[d] = upper ? frac[d] - 1.0f : frac[d];
        }
        corner[c] = grad(hash_cell(k, N), q, N);
    }
    if (N == 1) return mix(corner[0], corner[1], t[0]);
    // Cycles' SIMD order: 2D and 3D along x, then y, then z; 4D (AVX) along w first, then x, y, z.
    int n = 1 << N;
    if (N == 4) {
        n /= 2;
        for (int i = 0; i < n; ++i) corner[i] = mix_simd(corner[i], corner[i + n], t[3]);
    }
    for (int d = 0; d < 3 && n > 1; ++d) {
        n /= 2;
        for (int i = 0; i < n; ++i) corner[i] = mix_simd(corner[2 * i], corner[2 * i + 1], t[d]);
    }
    return corner[0];
}

float ensure_finite(float v) { return std::isfinite(v) ? v : 0.0f; }

}  // namespace

float perlin(float x) { return perlin_n<1>(&x); }
float perlin(const glm::vec2& p) {
    const float a[2] = {p.x, p.y};
    return perlin_n<2>(a);
}
float perlin(const glm::vec3& p) {
    const float a[3] = {p.x, p.y, p.z};
    return perlin_n<3>(a);
}
float perlin(const glm::vec4& p) {
    const float a[4] = {p.x, p.y, p.z, p.w};
    return perlin_n<4>(a);
}

// The scales bring each dimension's noise to about [−1, 1] (the OSL developers' measurements).
float snoise(float p) { return 0.2500f * ensure_finite(perlin(p)); }
float snoise(const glm::vec2& p) { return 0.6616f * ensure_finite(perlin(p)); }
float snoise(const glm::vec3& p) { return 0.9820f * ensure_finite(perlin(p)); }
float snoise(const glm::vec4& p) { return 0.8344f * ensure_finite(perlin(p)); }

float unoise(float p) { return 0.5f * snoise(p) + 0.5f; }
float unoise(const glm::vec2& p) { return 0.5f * snoise(p) + 0.5f; }
float unoise(const glm::vec3& p) { return 0.5f * snoise(p) + 0.5f; }
float unoise(const glm::vec4& p) { return 0.5f * snoise(p) + 0.5f; }

// --- fractal noise ------------------------------------------------------------------------------------------------

namespace {

template <typename P>
float fractal_noise_t(const P& p, float detail, float roughness) {
    float fscale = 1.0f, amp = 1.0f, maxamp = 0.0f, sum = 0.0f;
    // The clamp bounds the loop (NaN detail becomes 0).
    const float octaves = clamp(detail, 0.0f, 15.0f);
    const float gain = clamp(roughness, 0.0f, 1.0f);
    const int n = float_to_int(octaves);
    for (int i = 0; i <= n; ++i) {
        sum = std::fma(unoise(fscale * p), amp, sum);  // contracted in Cycles' build
        maxamp += amp;
        amp *= gain;
        fscale *= 2.0f;
    }
    const float rmd = octaves - std::floor(octaves);
    if (rmd == 0.0f) return sum / maxamp;
    // A fractional detail blends the normalised sums without and with one more octave.
    const float t = unoise(fscale * p);
    const float sum2 = (sum + t * amp) / (maxamp + amp);
    return (1.0f - rmd) * (sum / maxamp) + rmd * sum2;
}

}  // namespace

float fractal_noise(float p, float detail, float roughness) { return fractal_noise_t(p, detail, roughness); }
float fractal_noise(const glm::vec2& p, float detail, float roughness) {
    return fractal_noise_t(p, detail, roughness);
}
float fractal_noise(const glm::vec3& p, float detail, float roughness) {
    return fractal_noise_t(p, detail, roughness);
}
float fractal_noise(const glm::vec4& p, float detail, float roughness) {
    return fractal_noise_t(p, detail, roughness);
}

// --- the Noise Texture node ---------------------------------------------------------------------------------------

float random_float_offset(float seed) { return 100.0f + hash_float_to_float(seed) * 100.0f; }

namespace {
float offset_component(float seed, float i) { return 100.0f + hash_vec2_to_float(glm::vec2(seed, i)) * 100.0f; }
}  // namespace

glm::vec2 random_vec2_offset(float seed) { return {offset_component(seed, 0.0f), offset_component(seed, 1.0f)}; }
glm::vec3 random_vec3_offset(float seed) {
    return {offset_component(seed, 0.0f), offset_component(seed, 1.0f), offset_component(seed, 2.0f)};
}
glm::vec4 random_vec4_offset(float seed) {
    return {offset_component(seed, 0.0f), offset_component(seed, 1.0f), offset_component(seed, 2.0f),
            offset_component(seed, 3.0f)};
}

// The seeds each dimension uses: its distortion takes the first `dims` (one per axis; 1D uses seed 0 through
// random_float_offset), the colour's two channels the next two.
NoiseTextureResult noise_texture(float p, float detail, float roughness, float distortion, bool want_color) {
    // contracted in Cycles' build (unfused, its renders and ours differ by up to 2e-3 at detail 15)
    if (distortion != 0.0f) p = std::fma(snoise(p + random_float_offset(0.0f)), distortion, p);
    NoiseTextureResult r;
    r.value = fractal_noise(p, detail, roughness);
    if (want_color)
        r.color = {r.value, fractal_noise(p + random_float_offset(1.0f), detail, roughness),
                   fractal_noise(p + random_float_offset(2.0f), detail, roughness)};
    return r;
}

NoiseTextureResult noise_texture(const glm::vec2& co, float detail, float roughness, float distortion,
                                 bool want_color) {
    glm::vec2 p = co;
    if (distortion != 0.0f)
        p += glm::vec2(snoise(p + random_vec2_offset(0.0f)) * distortion,
                       snoise(p + random_vec2_offset(1.0f)) * distortion);
    NoiseTextureResult r;
    r.value = fractal_noise(p, detail, roughness);
    if (want_color)
        r.color = {r.value, fractal_noise(p + random_vec2_offset(2.0f), detail, roughness),
                   fractal_noise(p + random_vec2_offset(3.0f), detail, roughness)};
    return r;
}

NoiseTextureResult noise_texture(const glm::vec3& co, float detail, float roughness, float distortion,
                                 bool want_color) {
    glm::vec3 p = co;
    if (distortion != 0.0f)
        p += glm::vec3(snoise(p + random_vec3_offset(0.0f)) * distortion,
                       snoise(p + random_vec3_offset(1.0f)) * distortion,
                       snoise(p + random_vec3_offset(2.0f)) * distortion);
    NoiseTextureResult r;
    r.value = fractal_noise(p, detail, roughness);
    if (want_color)
        r.color = {r.value, fractal_noise(p + random_vec3_offset(3.0f), detail, roughness),
                   fractal_noise(p + random_vec3_offset(4.0f), detail, roughness)};
    return r;
}

NoiseTextureResult noise_texture(const glm::vec4& co, float detail, float roughness, float distortion,
                                 bool want_color) {
    glm::vec4 p = co;
    if (distortion != 0.0f)
        p += glm::vec4(snoise(p + random_vec4_offset(0.0f)) * distortion,
                       snoise(p + random_vec4_offset(1.0f)) * distortion,
                       snoise(p + random_vec4_offset(2.0f)) * distortion,
                       snoise(p + random_vec4_offset(3.0f)) * distortion);
    NoiseTextureResult r;
    r.value = fractal_noise(p, detail, roughness);
    if (want_color)
        r.color = {r.value, fractal_noise(p + random_vec4_offset(4.0f), detail, roughness),
                   fractal_noise(p + random_vec4_offset(5.0f), detail, roughness)};
    return r;
}

}  // namespace noise
}  // namespace ps
