// Colour helpers shared by the shader nodes: the HSV and HSL models and the colour-space constants, each as
// Blender 3.4's Cycles defines it (util/color.h, scene/shader.cpp), so that a node built on them gives Cycles'
// numbers, quirks included (hue of a grey is 0, HSV's v is the maximum even above 1, HSL's l is capped at 1).
// Internal to the shader program sources.
#pragma once
#include <glm/vec3.hpp>

namespace ps {

// Cycles' own min/max/clamp: `a < b ? a : b`. Unlike std::fmin they pass the second operand on NaN, so clamping
// a NaN gives the lower bound; the nodes rely on this to turn a NaN input into a finite output as Cycles does.
inline float cmin(float a, float b) { return a < b ? a : b; }
inline float cmax(float a, float b) { return a > b ? a : b; }
inline float cclamp(float a, float lo, float hi) { return cmin(cmax(a, lo), hi); }
inline float csaturate(float a) { return cclamp(a, 0.0f, 1.0f); }
inline glm::vec3 cmin(const glm::vec3& a, const glm::vec3& b) {
    return {cmin(a.x, b.x), cmin(a.y, b.y), cmin(a.z, b.z)};
}
inline glm::vec3 cmax(const glm::vec3& a, const glm::vec3& b) {
    return {cmax(a.x, b.x), cmax(a.y, b.y), cmax(a.z, b.z)};
}
inline glm::vec3 csaturate(const glm::vec3& a) { return {csaturate(a.x), csaturate(a.y), csaturate(a.z)}; }

// HSV and HSL, all components in [0, 1] for colours in [0, 1] (hue as a fraction of the circle).
glm::vec3 rgb_to_hsv(const glm::vec3& rgb);
glm::vec3 hsv_to_rgb(const glm::vec3& hsv);
glm::vec3 rgb_to_hsl(const glm::vec3& rgb);
glm::vec3 hsl_to_rgb(const glm::vec3& hsl);

// Luminance of a scene-linear colour: Cycles' rgb_to_y, which it derives from the OCIO config's XYZ transform
// (Blender 3.4's config: Rec.709 primaries, via its aces_interchange role), not the config's rounded luma line.
extern const glm::vec3 kRgbToY;
float cycles_luminance(const glm::vec3& rgb);

// CIE XYZ (D65) to scene-linear Rec.709, as Cycles 3.4 derives it for Blender's default config.
glm::vec3 xyz_to_rgb(const glm::vec3& xyz);

}  // namespace ps
