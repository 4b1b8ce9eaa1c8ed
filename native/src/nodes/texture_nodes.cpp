// The procedural texture ops of shader programs: Noise, Voronoi, Musgrave, Wave, Magic, Brick, Checker, Gradient
// and White Noise, each giving what Blender 3.4's Cycles gives (kernel/svm/noisetex.h, voronoi.h, musgrave.h,
// wave.h, magic.h, brick.h, checker.h, gradient.h, white_noise.h), so that a material renders as in Cycles. The
// noise primitives they share are in noise.cpp. Operand layouts are shader_program.h's table; every op checks its
// params first and writes zeros to all its outputs for a mode out of range. Loops are bounded whatever the
// inputs: octave counts are clamped as Cycles clamps them, cell scans have fixed sizes. Like noise.cpp, this file
// fuses a multiply-add only where Cycles' x86 build does (as std::fma) and forbids the compiler to fuse others.
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "nodes/noise.h"
#include "shader/op_args.h"

// No fusing but the explicit std::fma (noise.cpp says why).
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace ps {
namespace {

using noise::clamp;
using noise::float_to_int;
using noise::mix;

constexpr float kPiOver2 = 1.57079632679489661923f;
constexpr float kTwoPi = 6.28318530717958647692f;

float saturate(float a) { return clamp(a, 0.0f, 1.0f); }
float safe_divide(float a, float b) { return b != 0.0f ? a / b : 0.0f; }

// What a mode out of range gives: every output (of the kinds listed) zero. Returns true: the op is still ours.
bool invalid_mode(const OpArgs& a, const char* kinds) {
    for (int o = 0; kinds[o]; ++o) {
        if (kinds[o] == 'v')
            a.set(o, glm::vec3(0.0f));
        else
            a.set(o, 0.0f);
    }
    return true;
}

// --- Noise Texture ------------------------------------------------------------------------------------------------

bool noise_texture(const OpArgs& a) {
    const int dims = a.param(0);
    if (dims < 1 || dims > 4) return invalid_mode(a, "fv");
    const float scale = a.f(2), detail = a.f(3), roughness = a.f(4), distortion = a.f(5);
    const glm::vec3 v = a.v(0) * scale;
    const float w = a.f(1) * scale;
    const bool want_color = a.out[1] >= 0;
    noise::NoiseTextureResult r;
    switch (dims) {
        case 1: r = noise::noise_texture(w, detail, roughness, distortion, want_color); break;
        case 2: r = noise::noise_texture(glm::vec2(v.x, v.y), detail, roughness, distortion, want_color); break;
        case 3: r = noise::noise_texture(v, detail, roughness, distortion, want_color); break;
        default: r = noise::noise_texture(glm::vec4(v, w), detail, roughness, distortion, want_color); break;
    }
    a.set(0, r.value);
    a.set(1, r.color);
    return true;
}

// --- Voronoi Texture ----------------------------------------------------------------------------------------------
// Feature points: one per unit cell, at the cell's corner plus a hashed offset scaled by the randomness. F1 and
// F2 are the nearest and second nearest (scanning the 3^N neighbouring cells), Smooth F1 a smooth minimum over
// 5^N cells, Distance to Edge the distance to the nearest Voronoi cell boundary, N-Sphere Radius half the
// distance from the nearest point to its own nearest neighbour.

enum VoronoiFeature { kF1 = 0, kF2 = 1, kSmoothF1 = 2, kDistanceToEdge = 3, kNSphereRadius = 4 };
enum VoronoiMetric { kEuclidean = 0, kManhattan = 1, kChebychev = 2, kMinkowski = 3 };

struct VoronoiResult {
    float distance = 0.0f;
    glm::vec3 color{0.0f};
    glm::vec4 position{0.0f};  // as many components as the dimension; 1D: x
    float radius = 0.0f;
};

float smoothstep01(float x) {
    if (x < 0.0f) return 0.0f;
    if (x >= 1.0f) return 1.0f;
    return (3.0f - 2.0f * x) * (x * x);
}

// The smooth minimum's step: blends the running (distance, colour, position) towards a new point.
template <typename P>
void smooth_min_step(float smoothness, float d, const glm::vec3& color, const P& position, float& smooth_distance,
                     glm::vec3& smooth_color, P& smooth_position) {
    const float h = smoothstep01(0.5f + 0.5f * (smooth_distance - d) / smoothness);
    float correction = smoothness * h * (1.0f - h);
    smooth_distance = mix(smooth_distance, d, h) - correction;
    correction /= 1.0f + 3.0f * smoothness;
    smooth_color = smooth_color + h * (color - smooth_color) - correction;
    smooth_position = smooth_position + h * (position - smooth_position) - correction;
}

// 1D: the distance is |a − b| whatever the metric (Cycles ignores it).
VoronoiResult voronoi_1d(float w, int feature, float smoothness, float randomness) {
    const float cell = std::floor(w);
    const float local = w - cell;
    auto point = [&](float offset) { return offset + noise::hash_float_to_float(cell + offset) * randomness; };
    VoronoiResult r;
    switch (feature) {
        case kF1: {
            float min_d = 8.0f, target_offset = 0.0f, target = 0.0f;
            for (int i = -1; i <= 1; ++i) {
                const float offset = static_cast<float>(i);
                const float p = point(offset);
                const float d = std::fabs(p - local);
                if (d < min_d) min_d = d, target_offset = offset, target = p;
            }
            r.distance = min_d;
            r.color = noise::hash_float_to_color(cell + target_offset);
            r.position.x = target + cell;
            break;
        }
        case kSmoothF1: {
            float smooth_d = 8.0f, smooth_p = 0.0f;
            glm::vec3 smooth_c(0.0f);
            for (int i = -2; i <= 2; ++i) {
                const float offset = static_cast<float>(i);
                const float p = point(offset);
                smooth_min_step(smoothness, std::fabs(p - local), noise::hash_float_to_color(cell + offset), p,
                                smooth_d, smooth_c, smooth_p);
            }
            r.distance = smooth_d;
            r.color = smooth_c;
            r.position.x = cell + smooth_p;
            break;
        }
        case kF2: {
            float d1 = 8.0f, d2 = 8.0f, offset1 = 0.0f, offset2 = 0.0f, p1 = 0.0f, p2 = 0.0f;
            for (int i = -1; i <= 1; ++i) {
                const float offset = static_cast<float>(i);
                const float p = point(offset);
                const float d = std::fabs(p - local);
                if (d < d1) {
                    d2 = d1, offset2 = offset1, p2 = p1;
                    d1 = d, offset1 = offset, p1 = p;
                } else if (d < d2) {
                    d2 = d, offset2 = offset, p2 = p;
                }
            }
            r.distance = d2;
            r.color = noise::hash_float_to_color(cell + offset2);
            r.position.x = p2 + cell;
            break;
        }
        case kDistanceToEdge: {
            // In 1D the edges are the midpoints between this cell's point and its neighbours'.
            const float mid = point(0.0f);
            const float left = point(-1.0f);
            const float right = point(1.0f);
            const float to_left = std::fabs((mid + left) / 2.0f - local);
            const float to_right = std::fabs((mid + right) / 2.0f - local);
            r.distance = to_left < to_right ? to_left : to_right;
            break;
        }
        default: {  // kNSphereRadius
            float closest = 0.0f, closest_offset = 0.0f, min_d = 8.0f;
            for (int i = -1; i <= 1; ++i) {
                const float offset = static_cast<float>(i);
                const float p = point(offset);
                const float d = std::fabs(p - local);
                if (d < min_d) min_d = d, closest = p, closest_offset = offset;
            }
            min_d = 8.0f;
            float neighbour = 0.0f;
            for (int i = -1; i <= 1; ++i) {
                if (i == 0) continue;
                const float offset = static_cast<float>(i) + closest_offset;
                const float p = point(offset);
                const float d = std::fabs(closest - p);
                if (d < min_d) min_d = d, neighbour = p;
            }
            r.radius = std::fabs(neighbour - closest) / 2.0f;
            break;
        }
    }
    return r;
}

template <int N>
using Vec = glm::vec<N, float, glm::defaultp>;

glm::vec2 point_hash(const glm::vec2& c) { return noise::hash_vec2_to_vec2(c); }
glm::vec3 point_hash(const glm::vec3& c) { return noise::hash_vec3_to_vec3(c); }
glm::vec4 point_hash(const glm::vec4& c) { return noise::hash_vec4_to_vec4(c); }
glm::vec3 cell_color(const glm::vec2& c) { return noise::hash_vec2_to_color(c); }
glm::vec3 cell_color(const glm::vec3& c) { return noise::hash_vec3_to_color(c); }
glm::vec3 cell_color(const glm::vec4& c) { return noise::hash_vec4_to_color(c); }

// Cycles' len(): sqrt of the dot product, and normalize() as a division by it (not glm's inverse square root).
template <int N>
float length_of(const Vec<N>& v) {
    return std::sqrt(glm::dot(v, v));
}

template <int N>
float metric_distance(const Vec<N>& a, const Vec<N>& b, int metric, float exponent) {
    const Vec<N> d = a - b;
    switch (metric) {
        case kEuclidean: return length_of<N>(d);
        case kManhattan: {
            float s = std::fabs(d[0]);
            for (int i = 1; i < N; ++i) s += std::fabs(d[i]);
            return s;
        }
        case kChebychev: {
            float m = std::fabs(d[N - 1]);
            for (int i = N - 2; i >= 0; --i) {
                const float c = std::fabs(d[i]);
                m = c > m ? c : m;
            }
            return m;
        }
        default: {  // kMinkowski
            float s = std::pow(std::fabs(d[0]), exponent);
            for (int i = 1; i < N; ++i) s += std::pow(std::fabs(d[i]), exponent);
            return std::pow(s, 1.0f / exponent);
        }
    }
}

// The offset of neighbour `index` of the (2 reach + 1)^N around a cell, x varying fastest, then y, z, w: Cycles'
// scan order, which the smooth minimum and tie-breaking depend on.
template <int N>
Vec<N> neighbour_offset(int index, int reach) {
    Vec<N> o;
    const int side = 2 * reach + 1;
    for (int d = 0; d < N; ++d) {
        o[d] = static_cast<float>(index % side - reach);
        index /= side;
    }
    return o;
}

constexpr int ipow(int b, int e) { return e == 0 ? 1 : b * ipow(b, e - 1); }

template <int N>
VoronoiResult voronoi_nd(const Vec<N>& coord, int feature, int metric, float smoothness, float exponent,
                         float randomness) {
    const Vec<N> cell = glm::floor(coord);
    const Vec<N> local = coord - cell;
    auto point = [&](const Vec<N>& offset) { return offset + point_hash(cell + offset) * randomness; };
    constexpr int kNear = ipow(3, N), kSmooth = ipow(5, N);
    VoronoiResult r;
    Vec<N> position(0.0f);
    switch (feature) {
        case kF1: {
            float min_d = 8.0f;
            Vec<N> target_offset(0.0f), target(0.0f);
            for (int n = 0; n < kNear; ++n) {
                const Vec<N> offset = neighbour_offset<N>(n, 1);
                const Vec<N> p = point(offset);
                const float d = metric_distance<N>(p, local, metric, exponent);
                if (d < min_d) target_offset = offset, min_d = d, target = p;
            }
            r.distance = min_d;
            r.color = cell_color(cell + target_offset);
            position = target + cell;
            break;
        }
        case kSmoothF1: {
            float smooth_d = 8.0f;
            glm::vec3 smooth_c(0.0f);
            Vec<N> smooth_p(0.0f);
            for (int n = 0; n < kSmooth; ++n) {
                const Vec<N> offset = neighbour_offset<N>(n, 2);
                const Vec<N> p = point(offset);
                smooth_min_step(smoothness, metric_distance<N>(p, local, metric, exponent),
                                cell_color(cell + offset), p, smooth_d, smooth_c, smooth_p);
            }
            r.distance = smooth_d;
            r.color = smooth_c;
            position = cell + smooth_p;
            break;
        }
        case kF2: {
            float d1 = 8.0f, d2 = 8.0f;
            Vec<N> offset1(0.0f), offset2(0.0f), p1(0.0f), p2(0.0f);
            for (int n = 0; n < kNear; ++n) {
                const Vec<N> offset = neighbour_offset<N>(n, 1);
                const Vec<N> p = point(offset);
                const float d = metric_distance<N>(p, local, metric, exponent);
                if (d < d1) {
                    d2 = d1, offset2 = offset1, p2 = p1;
                    d1 = d, offset1 = offset, p1 = p;
                } else if (d < d2) {
                    d2 = d, offset2 = offset, p2 = p;
                }
            }
            r.distance = d2;
            r.color = cell_color(cell + offset2);
            position = p2 + cell;
            break;
        }
        case kDistanceToEdge: {
            // Euclidean whatever the metric: the nearest point, then the distance to each bisecting plane
            // between it and the others.
            Vec<N> to_closest(0.0f);
            float min_d = 8.0f;
            for (int n = 0; n < kNear; ++n) {
                const Vec<N> to_point = point(neighbour_offset<N>(n, 1)) - local;
                const float d = glm::dot(to_point, to_point);
                if (d < min_d) min_d = d, to_closest = to_point;
            }
            min_d = 8.0f;
            for (int n = 0; n < kNear; ++n) {
                const Vec<N> to_point = point(neighbour_offset<N>(n, 1)) - local;
                const Vec<N> perpendicular = to_point - to_closest;
                if (glm::dot(perpendicular, perpendicular) > 0.0001f) {
                    const float d = glm::dot((to_closest + to_point) / 2.0f, perpendicular / length_of<N>(perpendicular));
                    min_d = d < min_d ? d : min_d;
                }
            }
            r.distance = min_d;
            break;
        }
        default: {  // kNSphereRadius, Euclidean whatever the metric
            Vec<N> closest(0.0f), closest_offset(0.0f);
            float min_d = 8.0f;
            for (int n = 0; n < kNear; ++n) {
                const Vec<N> offset = neighbour_offset<N>(n, 1);
                const Vec<N> p = point(offset);
                const float d = length_of<N>(p - local);
                if (d < min_d) min_d = d, closest = p, closest_offset = offset;
            }
            min_d = 8.0f;
            Vec<N> neighbour(0.0f);
            const int centre = (kNear - 1) / 2;  // the zero offset
            for (int n = 0; n < kNear; ++n) {
                if (n == centre) continue;
                const Vec<N> offset = neighbour_offset<N>(n, 1) + closest_offset;
                const Vec<N> p = point(offset);
                const float d = length_of<N>(closest - p);
                if (d < min_d) min_d = d, neighbour = p;
            }
            r.radius = length_of<N>(neighbour - closest) / 2.0f;
            break;
        }
    }
    for (int d = 0; d < N; ++d) r.position[d] = position[d];
    return r;
}

bool voronoi_texture(const OpArgs& a) {
    const int dims = a.param(0), feature = a.param(1), metric = a.param(2);
    if (dims < 1 || dims > 4 || feature < 0 || feature > 4 || metric < 0 || metric > 3)
        return invalid_mode(a, "fvvff");
    const float scale = a.f(2);
    const float smoothness = clamp(a.f(3) / 2.0f, 0.0f, 0.5f);
    const float exponent = a.f(4);
    const float randomness = clamp(a.f(5), 0.0f, 1.0f);
    const glm::vec3 co = a.v(0) * scale;
    const float w = a.f(1) * scale;

    VoronoiResult r;
    switch (dims) {
        case 1: r = voronoi_1d(w, feature, smoothness, randomness); break;
        case 2: r = voronoi_nd<2>(glm::vec2(co.x, co.y), feature, metric, smoothness, exponent, randomness); break;
        case 3: r = voronoi_nd<3>(co, feature, metric, smoothness, exponent, randomness); break;
        default: r = voronoi_nd<4>(glm::vec4(co, w), feature, metric, smoothness, exponent, randomness); break;
    }
    // Positions back in the input's units (zero for a zero scale, as Cycles' safe division).
    glm::vec4 p(0.0f);
    if (scale != 0.0f) p = r.position / scale;
    a.set(0, r.distance);
    a.set(1, r.color);
    a.set(2, dims == 1 ? glm::vec3(0.0f) : glm::vec3(p.x, p.y, dims == 2 ? 0.0f : p.z));
    a.set(3, dims == 1 ? safe_divide(r.position.x, scale) : (dims == 4 ? p.w : 0.0f));
    a.set(4, r.radius);
    return true;
}

// --- Musgrave Texture ---------------------------------------------------------------------------------------------
// Signed-noise fractals from Musgrave's "Texturing and Modeling": H is the fractal dimension (the octaves'
// amplitude falls by lacunarity^−H), `octaves` is the node's Detail (already clamped to [0, 15]).

template <typename P>
float musgrave_fbm(P p, float H, float lacunarity, float octaves) {
    float value = 0.0f, pwr = 1.0f;
    const float pw_hl = std::pow(lacunarity, -H);
    const int n = float_to_int(octaves);
    for (int i = 0; i < n; ++i) {
        value += noise::snoise(p) * pwr;
        pwr *= pw_hl;
        p *= lacunarity;
    }
    const float rmd = octaves - std::floor(octaves);
    if (rmd != 0.0f) value += rmd * noise::snoise(p) * pwr;
    return value;
}

template <typename P>
float musgrave_multifractal(P p, float H, float lacunarity, float octaves) {
    float value = 1.0f, pwr = 1.0f;
    const float pw_hl = std::pow(lacunarity, -H);
    const int n = float_to_int(octaves);
    for (int i = 0; i < n; ++i) {
        value *= (pwr * noise::snoise(p) + 1.0f);
        pwr *= pw_hl;
        p *= lacunarity;
    }
    const float rmd = octaves - std::floor(octaves);
    if (rmd != 0.0f) value *= (rmd * pwr * noise::snoise(p) + 1.0f);
    return value;
}

template <typename P>
float musgrave_hetero_terrain(P p, float H, float lacunarity, float octaves, float offset) {
    const float pw_hl = std::pow(lacunarity, -H);
    float pwr = pw_hl;
    // The first octave unscaled; later ones scaled by the value so far (smooth lowlands, rough peaks).
    float value = offset + noise::snoise(p);
    p *= lacunarity;
    const int n = float_to_int(octaves);
    for (int i = 1; i < n; ++i) {
        value += (noise::snoise(p) + offset) * pwr * value;
        pwr *= pw_hl;
        p *= lacunarity;
    }
    const float rmd = octaves - std::floor(octaves);
    if (rmd != 0.0f) value += rmd * ((noise::snoise(p) + offset) * pwr * value);
    return value;
}

template <typename P>
float musgrave_hybrid_multifractal(P p, float H, float lacunarity, float octaves, float offset, float gain) {
    const float pw_hl = std::pow(lacunarity, -H);
    float pwr = 1.0f, value = 0.0f, weight = 1.0f;
    const int n = float_to_int(octaves);
    for (int i = 0; weight > 0.001f && i < n; ++i) {
        if (weight > 1.0f) weight = 1.0f;
        const float signal = (noise::snoise(p) + offset) * pwr;
        pwr *= pw_hl;
        value += weight * signal;
        weight *= gain * signal;
        p *= lacunarity;
    }
    const float rmd = octaves - std::floor(octaves);
    if (rmd != 0.0f && weight > 0.001f) {
        if (weight > 1.0f) weight = 1.0f;
        const float signal = (noise::snoise(p) + offset) * pwr;
        value += rmd * weight * signal;
    }
    return value;
}

// Cycles' ridged multifractal ignores the fractional part of the detail.
template <typename P>
float musgrave_ridged_multifractal(P p, float H, float lacunarity, float octaves, float offset, float gain) {
    const float pw_hl = std::pow(lacunarity, -H);
    float pwr = pw_hl;
    float signal = offset - std::fabs(noise::snoise(p));
    signal *= signal;
    float value = signal;
    const int n = float_to_int(octaves);
    for (int i = 1; i < n; ++i) {
        p *= lacunarity;
        const float weight = saturate(signal * gain);
        signal = offset - std::fabs(noise::snoise(p));
        signal *= signal;
        signal *= weight;
        value += signal * pwr;
        pwr *= pw_hl;
    }
    return value;
}

template <typename P>
float musgrave(int type, const P& p, float H, float lacunarity, float octaves, float offset, float gain) {
    switch (type) {
        case 0: return musgrave_multifractal(p, H, lacunarity, octaves);
        case 1: return musgrave_fbm(p, H, lacunarity, octaves);
        case 2: return musgrave_hybrid_multifractal(p, H, lacunarity, octaves, offset, gain);
        case 3: return musgrave_ridged_multifractal(p, H, lacunarity, octaves, offset, gain);
        default: return musgrave_hetero_terrain(p, H, lacunarity, octaves, offset);
    }
}

bool musgrave_texture(const OpArgs& a) {
    const int dims = a.param(0), type = a.param(1);
    if (dims < 1 || dims > 4 || type < 0 || type > 4) return invalid_mode(a, "f");
    const float scale = a.f(2);
    const float detail = clamp(a.f(3), 0.0f, 15.0f);
    const float dimension = std::fmax(a.f(4), 1e-5f);
    const float lacunarity = std::fmax(a.f(5), 1e-5f);
    const float offset = a.f(6), gain = a.f(7);
    const glm::vec3 co = a.v(0);
    const float w = a.f(1);
    float fac;
    switch (dims) {
        case 1: fac = musgrave(type, w * scale, dimension, lacunarity, detail, offset, gain); break;
        case 2: fac = musgrave(type, glm::vec2(co.x, co.y) * scale, dimension, lacunarity, detail, offset, gain); break;
        case 3: fac = musgrave(type, co * scale, dimension, lacunarity, detail, offset, gain); break;
        default: fac = musgrave(type, glm::vec4(co, w) * scale, dimension, lacunarity, detail, offset, gain); break;
    }
    a.set(0, fac);
    return true;
}

// --- Wave Texture -------------------------------------------------------------------------------------------------

bool wave_texture(const OpArgs& a) {
    const int type = a.param(0), bands_dir = a.param(1), rings_dir = a.param(2), profile = a.param(3);
    if (type < 0 || type > 1 || bands_dir < 0 || bands_dir > 3 || rings_dir < 0 || rings_dir > 3 || profile < 0 ||
        profile > 2)
        return invalid_mode(a, "vf");
    const float distortion = a.f(2), detail = a.f(3), detail_scale = a.f(4), detail_roughness = a.f(5);
    const float phase = a.f(6);
    // Cycles nudges the point off exact unit coordinates, where bands would otherwise flip on rounding. Its x86
    // build fuses the scale with the nudge: unfused, the renders of high detail and strong distortion differ by
    // up to 8e-4 (noise.cpp says more on matching Cycles' rounding).
    const glm::vec3 co = a.v(0);
    const float scale = a.f(1);
    const glm::vec3 p = glm::vec3(std::fma(co.x, scale, 0.000001f), std::fma(co.y, scale, 0.000001f),
                                  std::fma(co.z, scale, 0.000001f)) * 0.999999f;

    float n;
    if (type == 0) {
        switch (bands_dir) {
            case 0: n = p.x * 20.0f; break;
            case 1: n = p.y * 20.0f; break;
            case 2: n = p.z * 20.0f; break;
            default: n = (p.x + p.y + p.z) * 10.0f; break;
        }
    } else {
        // Rings about an axis: the distance from it (that axis's component dropped); spherical: from the origin.
        glm::vec3 rp = p;
        switch (rings_dir) {
            case 0: rp *= glm::vec3(0.0f, 1.0f, 1.0f); break;
            case 1: rp *= glm::vec3(1.0f, 0.0f, 1.0f); break;
            case 2: rp *= glm::vec3(1.0f, 1.0f, 0.0f); break;
            default: break;
        }
        n = std::sqrt(glm::dot(rp, rp)) * 20.0f;
    }
    n += phase;
    if (distortion != 0.0f)
        n += distortion * (noise::fractal_noise(p * detail_scale, detail, detail_roughness) * 2.0f - 1.0f);

    float f;
    if (profile == 0) {
        f = 0.5f + 0.5f * std::sin(n - kPiOver2);
    } else if (profile == 1) {
        n /= kTwoPi;
        f = n - std::floor(n);
    } else {
        n /= kTwoPi;
        f = std::fabs(n - std::floor(n + 0.5f)) * 2.0f;
    }
    a.set(0, glm::vec3(f));
    a.set(1, f);
    return true;
}

// --- Magic Texture ------------------------------------------------------------------------------------------------

bool magic_texture(const OpArgs& a) {
    const int depth = a.param(0);
    if (depth < 0 || depth > 10) return invalid_mode(a, "vf");  // Blender's range; Cycles stops at 10
    const glm::vec3 co = a.v(0);
    const float scale = a.f(1);
    float distortion = a.f(2);
    // Wrapped into one period first (as Cycles does): keeps huge coordinates finite and precise.
    const float px = std::fmod(co.x, kTwoPi), py = std::fmod(co.y, kTwoPi), pz = std::fmod(co.z, kTwoPi);
    float x = std::sin((px + py + pz) * 5.0f * scale);
    float y = std::cos((-px + py - pz) * 5.0f * scale);
    float z = -std::cos((-px - py + pz) * 5.0f * scale);
    // Each level of depth folds one component through a sine or cosine of the three.
    if (depth > 0) {
        x *= distortion;
        y *= distortion;
        z *= distortion;
        y = -std::cos(x - y + z) * distortion;
    }
    if (depth > 1) x = std::cos(x - y - z) * distortion;
    if (depth > 2) z = std::sin(-x - y - z) * distortion;
    if (depth > 3) x = -std::cos(-x + y - z) * distortion;
    if (depth > 4) y = -std::sin(-x + y + z) * distortion;
    if (depth > 5) y = -std::cos(-x + y + z) * distortion;
    if (depth > 6) x = std::cos(x + y + z) * distortion;
    if (depth > 7) z = std::sin(x + y - z) * distortion;
    if (depth > 8) x = -std::cos(-x - y + z) * distortion;
    if (depth > 9) y = -std::sin(x - y + z) * distortion;
    if (distortion != 0.0f) {
        distortion *= 2.0f;
        x /= distortion;
        y /= distortion;
        z /= distortion;
    }
    const glm::vec3 color(0.5f - x, 0.5f - y, 0.5f - z);
    a.set(0, color);
    a.set(1, (color.x + color.y + color.z) * (1.0f / 3.0f));
    return true;
}

// --- Brick Texture ------------------------------------------------------------------------------------------------

// Cycles' cheap integer noise for a brick's tint, in [0, 1).
float brick_noise(uint32_t n) {
    n = (n + 1013u) & 0x7fffffffu;
    n = (n >> 13) ^ n;
    const uint32_t nn = (n * (n * n * 60493u + 19990303u) + 1376312589u) & 0x7fffffffu;
    return 0.5f * (static_cast<float>(nn) / 1073741824.0f);
}

bool brick_texture(const OpArgs& a) {
    const int offset_frequency = a.param(0), squash_frequency = a.param(1);
    // Blender allows 1..99; 0 is harmless (no offset or squash, as in Cycles), negative is not a mode.
    if (offset_frequency < 0 || offset_frequency > 99 || squash_frequency < 0 || squash_frequency > 99)
        return invalid_mode(a, "vf");
    const glm::vec3 p = a.v(0) * a.f(4);
    glm::vec3 color1 = a.v(1);
    const glm::vec3 color2 = a.v(2), mortar_color = a.v(3);
    const float mortar_size = a.f(5), mortar_smooth = a.f(6), bias = a.f(7);
    float brick_width = a.f(8);
    const float row_height = a.f(9), offset_amount = a.f(10), squash_amount = a.f(11);

    const int32_t row = float_to_int(std::floor(p.y / row_height));
    float offset = 0.0f;
    if (offset_frequency && squash_frequency) {
        // C++ remainders, as in Cycles: negative rows count from their own end.
        brick_width *= (row % squash_frequency) ? 1.0f : squash_amount;
        offset = (row % offset_frequency) ? 0.0f : brick_width * offset_amount;
    }
    const int32_t brick = float_to_int(std::floor((p.x + offset) / brick_width));
    const float x = (p.x + offset) - brick_width * static_cast<float>(brick);
    const float y = p.y - row_height * static_cast<float>(row);

    // (row << 16) + (brick & 0xFFFF) in unsigned arithmetic: the same bits without signed-shift overflow.
    const uint32_t key = (static_cast<uint32_t>(row) << 16) + (static_cast<uint32_t>(brick) & 0xFFFFu);
    const float tint = saturate(brick_noise(key) + bias);
    const float min_xy = x < y ? x : y;
    const float min_far = (brick_width - x) < (row_height - y) ? (brick_width - x) : (row_height - y);
    float min_dist = min_xy < min_far ? min_xy : min_far;
    float mortar;
    if (min_dist >= mortar_size) {
        mortar = 0.0f;
    } else if (mortar_smooth == 0.0f) {
        mortar = 1.0f;
    } else {
        min_dist = 1.0f - min_dist / mortar_size;
        if (min_dist < mortar_smooth) {
            const float t = min_dist / mortar_smooth;
            const float tt = t * t;
            mortar = 3.0f * tt - 2.0f * tt * t;
        } else {
            mortar = 1.0f;
        }
    }
    if (mortar != 1.0f) color1 = (1.0f - tint) * color1 + tint * color2;
    a.set(0, color1 * (1.0f - mortar) + mortar_color * mortar);
    a.set(1, mortar);
    return true;
}

// --- Checker Texture ----------------------------------------------------------------------------------------------

bool checker_texture(const OpArgs& a) {
    glm::vec3 p = a.v(0) * a.f(3);
    // nudged off exact unit coordinates, as Cycles does
    p = (p + 0.000001f) * 0.999999f;
    // Parity of each cell index (Cycles takes abs() first, which keeps the parity; INT_MIN is even either way).
    const uint32_t xi = static_cast<uint32_t>(float_to_int(std::floor(p.x))) & 1u;
    const uint32_t yi = static_cast<uint32_t>(float_to_int(std::floor(p.y))) & 1u;
    const uint32_t zi = static_cast<uint32_t>(float_to_int(std::floor(p.z))) & 1u;
    const float f = (static_cast<uint32_t>(xi == yi) == zi) ? 1.0f : 0.0f;
    a.set(0, f == 1.0f ? a.v(1) : a.v(2));
    a.set(1, f);
    return true;
}

// --- Gradient Texture ---------------------------------------------------------------------------------------------

// shader_program.h's numbering: 0 linear, 1 quadratic, 2 easing, 3 diagonal, 4 spherical, 5 quadratic sphere,
// 6 radial.
bool gradient_texture(const OpArgs& a) {
    const int type = a.param(0);
    if (type < 0 || type > 6) return invalid_mode(a, "vf");
    const glm::vec3 p = a.v(0);
    float f = 0.0f;
    switch (type) {
        case 0: f = p.x; break;
        case 1: {
            const float r = std::fmax(p.x, 0.0f);
            f = r * r;
            break;
        }
        case 2: {
            const float r = std::fmin(std::fmax(p.x, 0.0f), 1.0f);
            const float t = r * r;
            f = 3.0f * t - 2.0f * t * r;
            break;
        }
        case 3: f = (p.x + p.y) * 0.5f; break;
        case 6: f = std::atan2(p.y, p.x) / kTwoPi + 0.5f; break;
        default: {
            // The bias makes a unit-length point exactly zero rather than rounding noise.
            const float r = std::fmax(0.999999f - std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 0.0f);
            f = type == 5 ? r * r : r;
            break;
        }
    }
    f = saturate(f);
    a.set(0, glm::vec3(f));
    a.set(1, f);
    return true;
}

// --- White Noise Texture ------------------------------------------------------------------------------------------

bool white_noise_texture(const OpArgs& a) {
    const int dims = a.param(0);
    if (dims < 1 || dims > 4) return invalid_mode(a, "fv");
    const glm::vec3 v = a.v(0);
    const float w = a.f(1);
    switch (dims) {
        case 1:
            a.set(0, noise::hash_float_to_float(w));
            a.set(1, noise::hash_float_to_color(w));
            break;
        case 2:
            a.set(0, noise::hash_vec2_to_float(glm::vec2(v.x, v.y)));
            a.set(1, noise::hash_vec2_to_color(glm::vec2(v.x, v.y)));
            break;
        case 3:
            a.set(0, noise::hash_vec3_to_float(v));
            a.set(1, noise::hash_vec3_to_color(v));
            break;
        default:
            a.set(0, noise::hash_vec4_to_float(glm::vec4(v, w)));
            a.set(1, noise::hash_vec4_to_color(glm::vec4(v, w)));
            break;
    }
    return true;
}

}  // namespace

bool run_texture_op(ShaderOp op, const OpArgs& a, const float* /*tables*/) {
    switch (op) {
        case ShaderOp::noise_texture: return noise_texture(a);
        case ShaderOp::voronoi_texture: return voronoi_texture(a);
        case ShaderOp::musgrave_texture: return musgrave_texture(a);
        case ShaderOp::wave_texture: return wave_texture(a);
        case ShaderOp::magic_texture: return magic_texture(a);
        case ShaderOp::brick_texture: return brick_texture(a);
        case ShaderOp::checker_texture: return checker_texture(a);
        case ShaderOp::gradient_texture: return gradient_texture(a);
        case ShaderOp::white_noise_texture: return white_noise_texture(a);
        default: return false;
    }
}

}  // namespace ps
