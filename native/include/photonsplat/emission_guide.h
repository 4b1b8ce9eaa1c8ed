// Where a distant light's photons are worth emitting. A sun's photons leave a disc covering the whole scene,
// but in an enclosed scene lit through openings (the atrium) most of them land on the roof and bounce back to
// the sky without ever being stored: they cost a path and add nothing. The guide is a piecewise-constant
// density over the two uniforms that place the photon on the disc, learnt from a few pilot paths per cell:
// cells whose pilots stored photons are chosen more often. Each photon's power is divided by how much more
// likely its cell was made (its pdf relative to uniform), so the estimate stays unbiased; a share of the
// uniform density is mixed in so that no cell is ever impossible, which also bounds that division.
#pragma once
#include <cstdint>
#include <vector>

namespace ps {

class EmissionGuide {
public:
    static constexpr int kCellsPerAxis = 32;
    static constexpr int kCells = kCellsPerAxis * kCellsPerAxis;
    static constexpr double kUniformShare = 0.1;  // ≥ this share of photons is emitted as without a guide

    EmissionGuide() = default;  // uniform: sample() leaves the point alone and returns weight 1

    // From each cell's usefulness (non-negative; kCells values, cell = x + kCellsPerAxis·y over (u1, u2)).
    // All zero (or not finite) gives the uniform guide.
    static EmissionGuide from_usefulness(const std::vector<double>& usefulness);

    // Moves (u1, u2), uniform in [0, 1)², into a cell chosen with `u_cell` and returns the photon's weight:
    // 1 / (pdf relative to uniform), at most 1 / kUniformShare.
    float sample(float u_cell, float& u1, float& u2) const;

    bool uniform() const { return cdf_.empty(); }
    double pdf(int cell) const;  // relative to uniform (1 everywhere for the uniform guide)

private:
    std::vector<float> cdf_;  // kCells running sums ending at 1; empty = uniform
    std::vector<float> pdf_;  // per cell, relative to uniform
};

}  // namespace ps
