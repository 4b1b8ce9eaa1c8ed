// The Sky Texture node of Cycles 3.4 (nodes/sky_texture.h): the host-side precomputation Cycles does per node
// (Preetham's Perez coefficients; Nishita's single-scattering sky texture and sun disc colours, which Blender's
// intern/sky computes) and the per-direction evaluation of svm/sky.h. Written from those definitions; the
// physical data are in nodes/sky_data.h.
#include "nodes/sky_texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "nodes/color_math.h"
#include "nodes/sky_data.h"

namespace ps {

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kHalfPi = 1.57079632679489661923f;
constexpr float kTwoPi = 6.28318530717958647692f;

float clampf(float v, float lo, float hi) { return std::min(std::max(v, lo), hi); }
float acos_clamped(float c) { return std::acos(clampf(c, -1.0f, 1.0f)); }

// Latitude (elevation) and longitude to a unit direction, z up.
glm::vec3 direction_at(float latitude, float longitude) {
    return glm::vec3(std::cos(latitude) * std::cos(longitude), std::cos(latitude) * std::sin(longitude),
                     std::sin(latitude));
}

// --- Preetham -------------------------------------------------------------------------------------------------

// Perez et al.'s luminance distribution with coefficients c[0..4], at zenith angle theta and sun angle gamma.
float perez(const float* c, float theta, float gamma) {
    const float cos_gamma = std::cos(gamma);
    return (1.0f + c[0] * std::exp(c[1] / std::cos(theta))) *
           (1.0f + c[2] * std::exp(c[3] * gamma) + c[4] * cos_gamma * cos_gamma);
}

// Preetham, Shirley and Smits (1999): the zenith's Y, x, y and the Perez coefficients of each for turbidity T
// and the sun at zenith angle theta_s, with Cycles' scale of Y (0.06) and its division by the distribution at
// the zenith.
void precompute_preetham(const float* s, float* out) {
    glm::vec3 sun(s[kSkySunDirectionX], s[kSkySunDirectionY], s[kSkySunDirectionZ]);
    const float length = glm::length(sun);
    sun = length > 0.0f && std::isfinite(length) ? sun / length : glm::vec3(0.0f, 0.0f, 1.0f);
    const float theta = acos_clamped(sun.z);
    const float phi = std::atan2(sun.x, sun.y);
    const float T = clampf(s[kSkyTurbidity], 1.0f, 10.0f);
    const float T2 = T * T, t1 = theta, t2 = theta * theta, t3 = t2 * theta;

    std::fill(out, out + kPreethamFloats, 0.0f);
    out[0] = phi;
    out[1] = theta;
    const float chi = (4.0f / 9.0f - T / 120.0f) * (kPi - 2.0f * theta);
    out[2] = ((4.0453f * T - 4.9710f) * std::tan(chi) - 0.2155f * T + 2.4192f) * 0.06f;
    out[3] = (0.00166f * t3 - 0.00375f * t2 + 0.00209f * t1) * T2 +
             (-0.02903f * t3 + 0.06377f * t2 - 0.03202f * t1 + 0.00394f) * T +
             (0.11693f * t3 - 0.21196f * t2 + 0.06052f * t1 + 0.25886f);
    out[4] = (0.00275f * t3 - 0.00610f * t2 + 0.00317f * t1) * T2 +
             (-0.04214f * t3 + 0.08970f * t2 - 0.04153f * t1 + 0.00516f) * T +
             (0.15346f * t3 - 0.26756f * t2 + 0.06670f * t1 + 0.26688f);
    float* Y = out + 5;
    float* x = out + 14;
    float* y = out + 23;
    // The paper's Table (A.2): coefficient = a·T + b, for A..E of Y, x and y.
    const float Yab[5][2] = {{0.1787f, -1.4630f}, {-0.3554f, 0.4275f}, {-0.0227f, 5.3251f}, {0.1206f, -2.5771f},
                             {-0.0670f, 0.3703f}};
    const float xab[5][2] = {{-0.0193f, -0.2592f}, {-0.0665f, 0.0008f}, {-0.0004f, 0.2125f}, {-0.0641f, -0.8989f},
                             {-0.0033f, 0.0452f}};
    const float yab[5][2] = {{-0.0167f, -0.2608f}, {-0.0950f, 0.0092f}, {-0.0079f, 0.2102f}, {-0.0441f, -1.6537f},
                             {-0.0109f, 0.0529f}};
    for (int k = 0; k < 5; ++k) {
        Y[k] = Yab[k][0] * T + Yab[k][1];
        x[k] = xab[k][0] * T + xab[k][1];
        y[k] = yab[k][0] * T + yab[k][1];
    }
    out[2] /= perez(Y, 0.0f, theta);
    out[3] /= perez(x, 0.0f, theta);
    out[4] /= perez(y, 0.0f, theta);
}

glm::vec3 evaluate_preetham(const float* d, const glm::vec3& dir) {
    float theta = acos_clamped(dir.z);
    const float phi = std::atan2(dir.x, dir.y);
    const float sun_phi = d[0], sun_theta = d[1];
    const float cos_psi =
        std::sin(sun_theta) * std::sin(theta) * std::cos(phi - sun_phi) + std::cos(sun_theta) * std::cos(theta);
    const float gamma = acos_clamped(cos_psi);
    theta = std::min(theta, kHalfPi - 0.001f);
    const float x = d[3] * perez(d + 14, theta, gamma);
    const float y = d[4] * perez(d + 23, theta, gamma);
    const float Y = d[2] * perez(d + 5, theta, gamma);
    // xyY → XYZ, with Cycles' guards against y = 0.
    const float X = y != 0.0f ? x / y * Y : 0.0f;
    const float Z = y != 0.0f && Y != 0.0f ? (1.0f - x - y) / y * Y : 0.0f;
    return glm::max(xyz_to_rgb(glm::vec3(X, Y, Z)), glm::vec3(0.0f));
}

// --- Nishita: the atmosphere --------------------------------------------------------------------------------
using namespace sky_data;

// Relative densities of air, aerosols and ozone at `height` metres above sea level: exponential profiles for the
// first two, a tent between 10 and 40 km peaking at 25 km for ozone.
glm::vec3 relative_density(float height) {
    constexpr float kPerLayer = 1.0f / 15000.0f;
    float ozone = 0.0f;
    if (height >= 10000.0f && height < 25000.0f)
        ozone = kPerLayer * height - 2.0f / 3.0f;
    else if (height >= 25000.0f && height < 40000.0f)
        ozone = 8.0f / 3.0f - kPerLayer * height;
    return glm::vec3(std::exp(-height / kRayleighScaleHeight), std::exp(-height / kMieScaleHeight), ozone);
}

float rayleigh_phase(float mu) { return 3.0f / (16.0f * kPi) * (1.0f + mu * mu); }

float mie_phase(float mu) {
    constexpr float g = kMieAnisotropy, g2 = g * g;
    return 3.0f * (1.0f - g2) * (1.0f + mu * mu) /
           (8.0f * kPi * (2.0f + g2) * std::pow(1.0f + g2 - 2.0f * g * mu, 1.5f));
}

// Whether the ray from `p` along `d` (unit) meets the Earth's sphere (only rays going down can).
bool earth_in_the_way(const glm::vec3& p, const glm::vec3& d) {
    if (d.z >= 0.0f) return false;
    const float b = 2.0f * glm::dot(d, p);
    const float c = glm::dot(p, p) - kEarthRadius * kEarthRadius;
    return b * b - 4.0f * c >= 0.0f;
}

// Distance from `p` inside the atmosphere along `d` (unit) to its top.
float distance_to_space(const glm::vec3& p, const glm::vec3& d) {
    const float b = 2.0f * glm::dot(d, p);
    const float c = glm::dot(p, p) - kAtmosphereRadius * kAtmosphereRadius;
    return 0.5f * (-b + std::sqrt(b * b - 4.0f * c));
}

// ∫ relative density along the ray from `p` to space (air, aerosols, ozone), by the scaled Gauss–Laguerre rule:
// densities fall off about exponentially along such a ray.
glm::vec3 optical_depth_to_space(const glm::vec3& p, const glm::vec3& d) {
    const float length = distance_to_space(p, d);
    glm::vec3 sum(0.0f);
    for (int i = 0; i < kQuadratureNodes; ++i) {
        const glm::vec3 q = p + (kQuadratureAt[i] * length) * d;
        sum += relative_density(glm::length(q) - kEarthRadius) * kQuadratureWeight[i];
    }
    return sum * length;
}

glm::vec3 spectrum_to_xyz(const float* spectrum) {
    glm::vec3 xyz(0.0f);
    for (int w = 0; w < kWavelengths; ++w)
        xyz += glm::vec3(kCieXyz[w][0], kCieXyz[w][1], kCieXyz[w][2]) * spectrum[w];
    return xyz * kWavelengthStep;
}

constexpr int kPrimarySteps = 32;

// Sunlight scattered once towards `eye` along the view ray `d`: the ray to space is cut into kPrimarySteps
// segments, each scattering, at its middle, the sunlight that reaches it (unless the Earth hides the sun)
// attenuated on both legs. `scale`: air, aerosol and ozone densities relative to the standard atmosphere.
glm::vec3 single_scattering_xyz(const glm::vec3& d, const glm::vec3& sun, const glm::vec3& eye, const glm::vec3& scale) {
    const float step = distance_to_space(eye, d) / float(kPrimarySteps);
    const glm::vec3 advance = step * d;
    const float mu = glm::dot(d, sun);
    const float phase_air = rayleigh_phase(mu), phase_aerosol = mie_phase(mu);
    float spectrum[kWavelengths] = {};
    glm::vec3 depth_from_eye(0.0f);
    glm::vec3 p = eye + 0.5f * advance;
    for (int i = 0; i < kPrimarySteps; ++i, p += advance) {
        const glm::vec3 density = scale * relative_density(glm::length(p) - kEarthRadius);
        depth_from_eye += step * density;
        if (earth_in_the_way(p, sun)) continue;
        const glm::vec3 depth = depth_from_eye + scale * optical_depth_to_space(p, sun);
        const float aerosol_extinction = depth.y * kMieExtinctionRatio * kMieScattering;
        const float aerosol_scattered = phase_aerosol * density.y * kMieScattering;
        for (int w = 0; w < kWavelengths; ++w) {
            const float transmittance =
                std::exp(-(depth.x * kRayleighScattering[w] + aerosol_extinction + depth.z * kOzoneAbsorption[w]));
            const float scattered = phase_air * density.x * kRayleighScattering[w] + aerosol_scattered;
            spectrum[w] += transmittance * scattered * kSunIrradiance[w] * step;
        }
    }
    return spectrum_to_xyz(spectrum);
}

// The sun's radiance (XYZ) seen from `eye` in direction `d`: its irradiance over the disc's solid angle,
// attenuated by air and aerosols (not ozone, as Blender's model).
glm::vec3 sun_xyz(const glm::vec3& d, const glm::vec3& eye, float air, float aerosols, float solid_angle) {
    const glm::vec3 depth = optical_depth_to_space(eye, d);
    float spectrum[kWavelengths];
    for (int w = 0; w < kWavelengths; ++w)
        spectrum[w] = kSunIrradiance[w] *
                      std::exp(-(kRayleighScattering[w] * depth.x * air +
                                 kMieExtinctionRatio * kMieScattering * depth.y * aerosols)) /
                      solid_angle;
    return spectrum_to_xyz(spectrum);
}

// The sky texture: kNishitaWidth longitudes × kNishitaHeight elevations from the horizon up, denser near the
// horizon (elevation grows with the square of the row), the sun at longitude 0; symmetric about the sun's
// meridian, so half the columns are computed and mirrored.
void compute_nishita_texture(float elevation, float altitude, const glm::vec3& scale, float* texels) {
    const glm::vec3 eye(0.0f, 0.0f, kEarthRadius + altitude);
    const glm::vec3 sun = direction_at(elevation, 0.0f);
    const float row_step = kHalfPi / float(kNishitaHeight);
    const float column_step = kTwoPi / float(kNishitaWidth);
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, kNishitaHeight, 2), [&](const tbb::blocked_range<int>& rows) {
            for (int y = rows.begin(); y < rows.end(); ++y) {
                const float v = float(y) / float(kNishitaHeight);
                const float latitude = (kHalfPi + 0.5f * row_step) * (v * v);
                float* row = texels + size_t(y) * kNishitaWidth * 3;
                for (int x = 0; x < kNishitaWidth / 2; ++x) {
                    const glm::vec3 d = direction_at(latitude, column_step * float(x) - kPi);
                    const glm::vec3 xyz = single_scattering_xyz(d, sun, eye, scale);
                    for (int column : {x, kNishitaWidth - 1 - x})
                        for (int k = 0; k < 3; ++k) row[column * 3 + k] = xyz[k];
                }
            }
        });
    });
}

// Textures by (elevation, altitude, air, dust, ozone), bit patterns, for the process's lifetime (a few at most
// in practice: one per distinct sky; bounded below).
using TextureKey = std::array<uint32_t, 5>;
std::mutex g_texture_mutex;
std::map<TextureKey, std::shared_ptr<const std::vector<float>>> g_textures;
constexpr size_t kMaxCachedTextures = 32;

std::shared_ptr<const std::vector<float>> nishita_texture(float elevation, float altitude, const glm::vec3& scale) {
    TextureKey key;
    const float values[5] = {elevation, altitude, scale.x, scale.y, scale.z};
    for (int i = 0; i < 5; ++i) std::memcpy(&key[i], &values[i], sizeof(float));
    {
        std::lock_guard<std::mutex> lock(g_texture_mutex);
        const auto found = g_textures.find(key);
        if (found != g_textures.end()) return found->second;
    }
    // Computed without the lock (the computation runs TBB tasks); two threads asking at once both compute the
    // same texture and the first inserted is kept.
    auto texels = std::make_shared<std::vector<float>>(size_t(kNishitaWidth) * kNishitaHeight * 3);
    compute_nishita_texture(elevation, altitude, scale, texels->data());
    std::lock_guard<std::mutex> lock(g_texture_mutex);
    if (g_textures.size() >= kMaxCachedTextures && g_textures.find(key) == g_textures.end()) g_textures.clear();
    return g_textures.emplace(key, std::move(texels)).first->second;
}

void precompute_nishita(bool sun_disc, const float* s, std::vector<float>& out) {
    // Blender's ranges for the node's properties, then Cycles' own clamps (altitude within [1 m, 60 km), the sun
    // at least 0.0005 rad wide).
    const float elevation = clampf(s[kSkySunElevation], -kHalfPi, kHalfPi);
    const float altitude = clampf(clampf(s[kSkyAltitude], 0.0f, 60000.0f), 1.0f, 59999.0f);
    const float air = clampf(s[kSkyAirDensity], 0.0f, 10.0f);
    const float dust = clampf(s[kSkyDustDensity], 0.0f, 10.0f);
    const float ozone = clampf(s[kSkyOzoneDensity], 0.0f, 10.0f);
    const float size = std::max(clampf(s[kSkySunSize], 0.0f, kHalfPi), 0.0005f);
    const float intensity = clampf(s[kSkySunIntensity], 0.0f, 1e30f);
    float rotation = std::fmod(s[kSkySunRotation], kTwoPi);
    if (!std::isfinite(rotation)) rotation = 0.0f;
    if (rotation < 0.0f) rotation += kTwoPi;
    rotation = kTwoPi - rotation;

    // The sun disc's colour at its lower and upper edges (clamped to the horizon), between which the kernel
    // interpolates by elevation.
    const glm::vec3 eye(0.0f, 0.0f, kEarthRadius + altitude);
    const float half = 0.5f * size;
    const float solid_angle = kTwoPi * (1.0f - std::cos(half));
    const glm::vec3 bottom = sun_xyz(direction_at(std::max(elevation - half, 0.0f), 0.0f), eye, air, dust, solid_angle);
    const glm::vec3 top = sun_xyz(direction_at(std::max(elevation + half, 0.0f), 0.0f), eye, air, dust, solid_angle);
    const float header[kNishitaHeaderFloats] = {bottom.x,  bottom.y, bottom.z, top.x, top.y, top.z, elevation,
                                                rotation, sun_disc ? size : -1.0f, intensity};
    out.insert(out.end(), header, header + kNishitaHeaderFloats);
    const auto texture = nishita_texture(elevation, altitude, glm::vec3(air, dust, ozone));
    out.insert(out.end(), texture->begin(), texture->end());
}

// Cycles' bilinear image lookup with its "extend" extension (texel centres at (i + 0.5) / size, indices clamped
// to the image).
glm::vec3 lookup_bilinear(const float* texels, float u, float v) {
    const auto split = [](float t, int size, int& i0, int& i1) {
        float x = t * float(size) - 0.5f;
        x = std::isfinite(x) ? clampf(x, -2.0f, float(size) + 1.0f) : 0.0f;
        int i = static_cast<int>(x) - (x < 0.0f ? 1 : 0);
        const float f = x - float(i);
        i0 = std::clamp(i, 0, size - 1);
        i1 = std::clamp(i + 1, 0, size - 1);
        return f;
    };
    int x0, x1, y0, y1;
    const float fx = split(u, kNishitaWidth, x0, x1);
    const float fy = split(v, kNishitaHeight, y0, y1);
    const auto at = [&](int x, int y) {
        const float* t = texels + (size_t(y) * kNishitaWidth + x) * 3;
        return glm::vec3(t[0], t[1], t[2]);
    };
    return (1.0f - fy) * ((1.0f - fx) * at(x0, y0) + fx * at(x1, y0)) + fy * ((1.0f - fx) * at(x0, y1) + fx * at(x1, y1));
}

glm::vec3 evaluate_nishita(const float* d, const glm::vec3& dir) {
    const glm::vec3 pixel_bottom(d[0], d[1], d[2]), pixel_top(d[3], d[4], d[5]);
    const float sun_elevation = d[6], sun_rotation = d[7], diameter = d[8], intensity = d[9];
    const float* texels = d + kNishitaHeaderFloats;
    const float theta = acos_clamped(dir.z);
    const float phi = std::atan2(dir.x, dir.y);
    // Texture column: the azimuth relative to the sun's.
    float u = (phi + kPi + sun_rotation) / kTwoPi;
    if (u > 1.0f) u -= 1.0f;
    glm::vec3 xyz(0.0f);
    if (dir.z >= 0.0f) {
        const glm::vec3 sun = direction_at(sun_elevation, sun_rotation + kHalfPi);
        // The angle between dir and the sun, robust near 0 (and, as Cycles, of dir as it is, not normalised).
        const float to_sun = 2.0f * std::atan2(glm::length(dir - sun), glm::length(dir + sun));
        const float half = 0.5f * diameter;
        const float elevation = kHalfPi - theta;
        if (diameter >= 0.0f && to_sun < half) {
            // The disc, coloured between its edges' colours by elevation (the part below the horizon cut off),
            // darkened towards the limb.
            if (sun_elevation + half > 0.0f) {
                const float t = sun_elevation - half > 0.0f ? (elevation - sun_elevation) / diameter + 0.5f
                                                            : elevation / (sun_elevation + half);
                xyz = ((1.0f - t) * pixel_bottom + t * pixel_top) * intensity;
            }
            const float r = to_sun / half;
            xyz *= 1.0f - 0.6f * (1.0f - std::sqrt(1.0f - r * r));
        } else {
            // More rows near the horizon: the row goes with the square root of the elevation.
            xyz = lookup_bilinear(texels, u, std::sqrt(std::max(elevation / kHalfPi, 0.0f)));
        }
    } else if (dir.z >= -0.4f) {
        // Below the horizon the lowest row fades out cubically to black at z = −0.4.
        float fade = 1.0f + 2.5f * dir.z;
        fade = fade * fade * fade;
        xyz = lookup_bilinear(texels, u, -0.5f) * fade;
    }
    return glm::max(xyz_to_rgb(xyz), glm::vec3(0.0f));
}

}  // namespace

int64_t sky_precomputed_floats(int32_t type) {
    switch (type) {
        case kSkyPreetham:
        case kSkyHosekWilkie: return kPreethamFloats;
        case kSkyNishita: return kNishitaFloats;
        default: return 0;
    }
}

void precompute_sky(int32_t type, bool sun_disc, const float* settings, std::vector<float>& out) {
    float s[kSkySettingsFloats];
    for (int i = 0; i < kSkySettingsFloats; ++i) s[i] = std::isfinite(settings[i]) ? settings[i] : 0.0f;
    if (type == kSkyNishita) {
        precompute_nishita(sun_disc, s, out);
    } else if (type == kSkyPreetham || type == kSkyHosekWilkie) {
        float data[kPreethamFloats];
        precompute_preetham(s, data);
        for (float& v : data)
            if (!std::isfinite(v)) v = 0.0f;
        out.insert(out.end(), data, data + kPreethamFloats);
    }
}

glm::vec3 evaluate_sky(int32_t type, const float* precomputed, const glm::vec3& dir) {
    if (!std::isfinite(dir.x) || !std::isfinite(dir.y) || !std::isfinite(dir.z)) return glm::vec3(0.0f);
    glm::vec3 c(0.0f);
    if (type == kSkyNishita)
        c = evaluate_nishita(precomputed, dir);
    else if (type == kSkyPreetham || type == kSkyHosekWilkie)
        c = evaluate_preetham(precomputed, dir);
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(c[k])) c[k] = 0.0f;
    return c;
}

bool run_sky_op(ShaderOp op, const OpArgs& a, const float* tables) {
    if (op != ShaderOp::sky_texture) return false;
    const int32_t offset = a.param(3);
    // -1: a program that finalize_program has not seen (never in a scene): black, never a precomputation here.
    a.set(0, offset < 0 ? glm::vec3(0.0f) : evaluate_sky(a.param(0), tables + offset, a.v(0)));
    return true;
}

}  // namespace ps
