// The world as a light source: an importance-sampling distribution over an equirectangular radiance map, as
// Cycles' background light (kernel/light/background.h) samples its background map.
//
// Conventions (Cycles' equirectangular mapping, kernel/camera/projection.h; directions in Blender's world
// space, +Z up):
//   u = (atan2(d.y, d.x) - π) / (-2π)   u = 0 (and 1) towards -X, 0.25 towards +Y, 0.5 towards +X, 0.75 towards -Y
//   v = (acos(d.z) - π) / (-π)           v = 0 at -Z (nadir), 0.5 on the horizon, 1 at +Z (zenith); θ = π(1 - v)
// A map of width × height cells covers u ∈ [0, 1] left to right and v ∈ [0, 1] from row 0 up: row 0 is the
// BOTTOM of the sky (next to -Z) and row height-1 the top (next to +Z), column 0 starts at -X. This is the order
// of Blender's image pixels (bottom row first), so an Environment Texture's pixels can be handed over as they are.
// Texel (x, y) is rgb[3 * (y * width + x) + c]; its centre is at u = (x + ½)/width, v = (y + ½)/height.
//
// The distribution is piecewise constant in (u, v): cell (x, y) is chosen with probability ∝
// max(luminance, 0) × sin θ of its centre (luminance = 0.2126 R + 0.7152 G + 0.0722 B, Rec. 709 as Blender's
// default colour space), then a point uniformly inside it. Its density per unit solid angle is the uv density
// times the Jacobian 1 / (2π² sin θ), with sin θ at the direction itself (not the cell centre), so pdf() is
// exact for the sampler and grows as 1/sin θ towards the poles, where it is integrable. Directions exactly at
// ±Z (sin θ = 0) get pdf 0, as in Cycles. The probabilities are the differences of the stored (float) CDFs,
// so pdf() is the density sample() really draws with, also for cells too faint for a float CDF to reach
// (they get pdf 0, and a caller's BSDF sampling, weighted by MIS, accounts for them alone).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace ps {

// Cycles' direction_to_equirectangular for a direction of any non-zero length: (u, v) ∈ [0, 1]². The zero or a
// non-finite vector gives (0, 0), as in Cycles.
glm::vec2 direction_to_equirectangular(const glm::vec3& direction);
// Cycles' equirectangular_to_direction: the unit direction of (u, v).
glm::vec3 equirectangular_to_direction(float u, float v);

// Rec. 709 luminance, the weight of a texel (as Cycles' background map with Blender's default colour space).
inline float environment_luminance(const glm::vec3& rgb) {
    return 0.2126f * rgb.x + 0.7152f * rgb.y + 0.0722f * rgb.z;
}

struct EnvironmentSample {
    glm::vec3 direction{0.0f, 0.0f, 1.0f};  // unit, world space (+Z up), the direction light comes FROM
    float pdf = 0.0f;                       // per unit solid angle; 0 only for a zero map: skip it
    glm::vec3 radiance{0.0f};               // of the map's cell the direction lies in (nearest, as radiance())
};

// Immutable once built: sample(), pdf() and radiance() may be called from any number of threads at once.
class EnvironmentDistribution {
public:
    // `rgb`: width × height × 3 linear radiances in the order above (row 0 at the bottom). Width and height
    // at least 1 (a 1 × 1 map is a constant sky); texels must be finite (ps::InvalidInput names the first that
    // is not); negative luminance weighs 0. Taken by value so that a caller can move a large map in.
    // O(width × height) time; memory: the map itself plus a float per cell for the CDFs.
    EnvironmentDistribution(int width, int height, std::vector<float> rgb);

    // Bakes `radiance_of_direction(const glm::vec3& unit_direction) -> glm::vec3` at every cell's centre
    // direction (equirectangular_to_direction((x + ½)/width, (y + ½)/height)): how the world's node program
    // becomes a map.
    template <class F>
    static EnvironmentDistribution from_function(int width, int height, F&& radiance_of_direction) {
        std::vector<float> rgb(checked_texel_count(width, height) * 3);
        for (int y = 0; y < height; ++y) {
            const float v = (static_cast<float>(y) + 0.5f) / static_cast<float>(height);
            for (int x = 0; x < width; ++x) {
                const float u = (static_cast<float>(x) + 0.5f) / static_cast<float>(width);
                const glm::vec3 value = radiance_of_direction(equirectangular_to_direction(u, v));
                const size_t at = 3 * (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x));
                rgb[at] = value.x;
                rgb[at + 1] = value.y;
                rgb[at + 2] = value.z;
            }
        }
        return EnvironmentDistribution(width, height, std::move(rgb));
    }

    // u1 picks the column within the row, u2 the row (Cycles' randu, randv); both in [0, 1), values outside
    // are clamped. The returned pdf and radiance are pdf(direction) and radiance(direction) of the returned
    // direction, bit for bit, so MIS weights agree whichever technique found a direction; the pdf is > 0 for
    // every sample of a non-zero map (a draw whose float direction would round across its cell's edge or onto
    // a pole, about one in a million, is moved a thousandth of the cell inside). A zero map returns pdf 0
    // (direction +Z, radiance 0): skip the sample.
    EnvironmentSample sample(float u1, float u2) const;
    // The same direction and pdf without the radiance (left 0): for a renderer that evaluates the world's shader
    // itself, which saves a read of the map per sample.
    EnvironmentSample sample_direction(float u1, float u2) const;

    // Solid-angle density with which sample() draws `direction` (any non-zero length); 0 where the map weighs
    // 0, at ±Z, for a zero map and for a zero or non-finite vector.
    float pdf(const glm::vec3& direction) const;

    // The map's radiance in `direction`: NEAREST texel (the cell the direction lies in, as the piecewise
    // constant distribution sees it), 0 for a zero or non-finite vector. For tests and cheap previews: the
    // renderer evaluates the world's shader itself and uses the map only for sampling, as Cycles does.
    glm::vec3 radiance(const glm::vec3& direction) const;

    // ∫ max(luminance, 0) dω over the sphere of the map as radiance() reconstructs it (each cell's exact solid
    // angle, 2π/width × (cos θ_low - cos θ_high)) [W m⁻² sr⁻¹ × sr]: to choose between light sources.
    double integral() const { return integral_; }

    int width() const { return width_; }
    int height() const { return height_; }
    bool is_zero() const { return integral_ <= 0.0; }  // nothing to sample: sample() and pdf() give 0

private:
    static size_t checked_texel_count(int width, int height);  // refuses sizes < 1 or past memory's reach
    // The cell (x, y) of a unit-or-not direction and its sin θ; false for the zero or a non-finite vector.
    bool locate(const glm::vec3& direction, int& x, int& y, double& sin_theta) const;
    float cell_pdf(int x, int y, double sin_theta) const;
    glm::vec3 texel(int x, int y) const;

    int width_ = 0;
    int height_ = 0;
    std::vector<float> rgb_;           // the map, as given
    std::vector<double> marginal_;     // height + 1: marginal_[y] = P(row < y); 0 … 1
    std::vector<float> conditional_;   // height × (width + 1): per row, P(column < x | row); 0 … 1
    double integral_ = 0.0;
};

}  // namespace ps
