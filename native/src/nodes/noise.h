// The noise primitives of Blender 3.4's Cycles (kernel/svm/noise.h, fractal_noise.h, noisetex.h and util/hash.h),
// reimplemented so that the procedural textures (texture_nodes.cpp) give Cycles' values: the same integer hash
// (Bob Jenkins' lookup3, as Cycles seeds it), the same Perlin gradients and lattice, the same output scales, the
// same fractal sums, and as far as it shows, the same rounding as the x86 AVX2 kernel Blender 3.4 runs
// (noise.cpp says why that matters at high detail). Cycles 3.4 has no coordinate wrapping for precision (later
// versions added it): far from the origin the lattice coarsens exactly as it does in 3.4.
//
// Non-finite and huge coordinates: Cycles converts the lattice cell with a truncating float→int conversion,
// which on x86 gives INT_MIN for NaN and anything beyond int's range. float_to_int reproduces that without the
// undefined behaviour of a C++ cast, and lattice arithmetic is unsigned (wrapping as Cycles' does in practice).
#pragma once
#include <cstdint>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace ps {
namespace noise {

// --- float helpers with Cycles' semantics -------------------------------------------------------------------------

// (int)f as x86's cvttss2si does it: truncation toward zero; NaN and values outside int's range give INT_MIN.
inline int32_t float_to_int(float f) {
    // written so that NaN fails the range test too
    if (f >= -2147483648.0f && f < 2147483648.0f) return static_cast<int32_t>(f);
    return INT32_MIN;
}
// Cycles' min(max(a, lo), hi) with its (a > b ? a : b) comparisons: a NaN `a` gives `lo`.
inline float clamp(float a, float lo, float hi) {
    const float m = a > lo ? a : lo;
    return m < hi ? m : hi;
}
// Cycles' mix: a + t (b − a), never fused (noise.cpp says why; so not inline here).
float mix(float a, float b, float t);

// --- hashes (util/hash.h) -----------------------------------------------------------------------------------------

uint32_t hash_uint(uint32_t kx);
uint32_t hash_uint2(uint32_t kx, uint32_t ky);
uint32_t hash_uint3(uint32_t kx, uint32_t ky, uint32_t kz);
uint32_t hash_uint4(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw);

// A hash as a float in [0, 1] (both ends included, as Cycles' uint_to_float_incl).
float hash_uint_to_float(uint32_t kx);
float hash_uint2_to_float(uint32_t kx, uint32_t ky);
float hash_uint3_to_float(uint32_t kx, uint32_t ky, uint32_t kz);
float hash_uint4_to_float(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw);

// Floats hashed by their bit patterns (so 0.0 and −0.0 differ, as in Cycles).
float hash_float_to_float(float k);
float hash_vec2_to_float(const glm::vec2& k);
float hash_vec3_to_float(const glm::vec3& k);
float hash_vec4_to_float(const glm::vec4& k);

// One independent hash per component: Voronoi's feature points.
glm::vec2 hash_vec2_to_vec2(const glm::vec2& k);
glm::vec3 hash_vec3_to_vec3(const glm::vec3& k);
glm::vec4 hash_vec4_to_vec4(const glm::vec4& k);

// A colour per cell: Voronoi's and White Noise's Color outputs.
glm::vec3 hash_float_to_color(float k);
glm::vec3 hash_vec2_to_color(const glm::vec2& k);
inline glm::vec3 hash_vec3_to_color(const glm::vec3& k) { return hash_vec3_to_vec3(k); }
glm::vec3 hash_vec4_to_color(const glm::vec4& k);

// --- Perlin noise (svm/noise.h) -----------------------------------------------------------------------------------

// Raw gradient noise, before the output scale; roughly in [−1, 1] after it.
float perlin(float x);
float perlin(const glm::vec2& p);
float perlin(const glm::vec3& p);
float perlin(const glm::vec4& p);

// Signed noise: the raw noise times the experimentally found scale of its dimension (0.25, 0.6616, 0.9820,
// 0.8344), a non-finite result (from non-finite input) replaced by 0.
float snoise(float p);
float snoise(const glm::vec2& p);
float snoise(const glm::vec3& p);
float snoise(const glm::vec4& p);
// Unsigned noise: 0.5 snoise + 0.5.
float unoise(float p);
float unoise(const glm::vec2& p);
float unoise(const glm::vec3& p);
float unoise(const glm::vec4& p);

// --- fractal noise (svm/fractal_noise.h) --------------------------------------------------------------------------

// The sum of unsigned noise octaves at doubling frequency and `roughness` times the amplitude each, normalised
// by the amplitudes' sum. `detail` (clamped to [0, 15]) counts octaves beyond the first; its fraction blends
// in one more octave.
float fractal_noise(float p, float detail, float roughness);
float fractal_noise(const glm::vec2& p, float detail, float roughness);
float fractal_noise(const glm::vec3& p, float detail, float roughness);
float fractal_noise(const glm::vec4& p, float detail, float roughness);

// --- the Noise Texture node (svm/noisetex.h) ----------------------------------------------------------------------

// Seeds for the noise: Cycles' noise has no seed, so the distortion and the colour channels read it at fixed
// offsets, each component in [100, 200] (hash of the seed; large enough to decorrelate, small enough to keep
// precision).
float random_float_offset(float seed);
glm::vec2 random_vec2_offset(float seed);
glm::vec3 random_vec3_offset(float seed);
glm::vec4 random_vec4_offset(float seed);

// The node at already scaled coordinates: the value (Fac) and, when `want_color`, the colour (value and two
// more fractal noises at offsets). `distortion` displaces the coordinates by signed noise first.
struct NoiseTextureResult {
    float value = 0.0f;
    glm::vec3 color{0.0f};
};
NoiseTextureResult noise_texture(float p, float detail, float roughness, float distortion, bool want_color);
NoiseTextureResult noise_texture(const glm::vec2& p, float detail, float roughness, float distortion, bool want_color);
NoiseTextureResult noise_texture(const glm::vec3& p, float detail, float roughness, float distortion, bool want_color);
NoiseTextureResult noise_texture(const glm::vec4& p, float detail, float roughness, float distortion, bool want_color);

}  // namespace noise
}  // namespace ps
