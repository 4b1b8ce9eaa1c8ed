// The Sky Texture node (Cycles 3.4's svm/sky.h and the host-side precomputation of its SkyTextureNode): the
// sky_texture op of shader_program.h. Internal to the shader program sources.
//
// The op's settings (tables, kSkySettingsFloats floats at params[2]) are the node's properties. Everything the
// node precomputes on the host, as Cycles does once per compiled node, is computed once per program by
// finalize_program and appended to the program's tables at params[3]:
//   Preetham (and Hosek / Wilkie, evaluated as Preetham): kPreethamFloats floats: sun phi, sun theta, zenith
//     Y, x, y, then the Perez coefficients of Y, x and y (9 each, 5 used);
//   Nishita: kNishitaHeaderFloats floats: the sun disc's XYZ at its bottom and top edge (pixel_bottom,
//     pixel_top), sun elevation, sun rotation (as the kernel wants it: 2π − the node's rotation wrapped to
//     [0, 2π)), the angular diameter (−1 without a sun disc), the sun intensity; then the sky's XYZ texture,
//     kNishitaWidth × kNishitaHeight × 3 floats, row-major from the horizon up, looked up bilinearly.
// The Nishita texture depends only on sun elevation, altitude and the three densities: textures are kept in a
// process-wide cache keyed by those (thread-safe), so several materials or programs with one sky compute it once.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "shader/op_args.h"

namespace ps {

enum SkySetting : int {
    kSkySunDirectionX = 0,
    kSkySunDirectionY,
    kSkySunDirectionZ,
    kSkyTurbidity,
    kSkyGroundAlbedo,
    kSkySunSize,
    kSkySunIntensity,
    kSkySunElevation,
    kSkySunRotation,
    kSkyAltitude,
    kSkyAirDensity,
    kSkyDustDensity,
    kSkyOzoneDensity,
    kSkySettingsFloats
};

enum SkyType : int { kSkyPreetham = 0, kSkyHosekWilkie = 1, kSkyNishita = 2 };

constexpr int kPreethamFloats = 32;
constexpr int kNishitaWidth = 512;
constexpr int kNishitaHeight = 128;
constexpr int kNishitaHeaderFloats = 10;
constexpr int64_t kNishitaFloats = kNishitaHeaderFloats + int64_t(kNishitaWidth) * kNishitaHeight * 3;

// How many precomputed floats a sky of `type` reads (0 for an unknown type).
int64_t sky_precomputed_floats(int32_t type);

// The precomputed data of a sky of `type` with `sun_disc` and `settings` (kSkySettingsFloats floats), appended
// to `out`. Settings are clamped to the node's ranges in Blender first.
void precompute_sky(int32_t type, bool sun_disc, const float* settings, std::vector<float>& out);

// The sky's colour (scene-linear Rec.709) in direction `dir` (not normalised, as Cycles: its length matters on
// a surface), from the precomputed data. Finite for any input.
glm::vec3 evaluate_sky(int32_t type, const float* precomputed, const glm::vec3& dir);

bool run_sky_op(ShaderOp op, const OpArgs& a, const float* tables);

}  // namespace ps
