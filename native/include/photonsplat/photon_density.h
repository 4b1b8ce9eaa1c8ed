// Radius levels: photons that glossy or sharp parts focused, where they gather densely, splat with a smaller radius
// (RenderSettings::adaptive_radius).
//
// One radius for every photon blurs a focused caustic by that radius, chosen for the scene's ordinary light: a glass
// ball's caustic a few pixels wide on a floor came out at 0.26 of the reference in its centre 2 × 2 pixels
// (tests/native/test_photon_density.cpp). Where photons are many times denser than usual, a smaller disc still
// holds as many of them as a usual disc does, so it is no noisier and far less blurred. Each photon is given a
// level k: it splats with radius / 2^k.
//
// Which photons. Only light whose last scatter (transparency aside) was a glossy, mirror or refracting part can be
// focused (kAfterGlossy): these are the candidates; every other photon keeps the radius, and a scene without such
// parts pays for nothing but a look at the flags.
//
// Density. Photons are tallied on a grid of cells of the radius's size; a photon's box is the 2 × 2 × 2 cells
// nearest it (about the kernel's diameter wide), and what counts is the box's effective number of photons,
// (Σw)² / Σw² with w a photon's power (luminance): a box of a few strong photons and many weak ones is as noisy as
// a few equal ones. The typical number is taken over all photons (every stride-th of them, at most kTypicalSample,
// times the stride) as the median over the lit surface, not over photons (which would make a caustic holding most
// photons "typical"): each photon weighs as the area it stands for, 1 / its box's count. A candidate's own number
// is among the candidates alone, since a level's splat holds only its own photons; where it is 4^k times the typical
// one or more (and 4^k times kMinTypicalCount), the candidate takes level k, up to kRadiusLevels − 1.
//
// Every level's photons are splatted by the same method with that level's radius, and each level's light is
// corrected for boundaries with its own radius (render.cpp): the estimate stays consistent, since every radius
// shrinks with the iteration's.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "photonsplat/photons.h"

namespace ps {

struct Stats;

constexpr int kRadiusLevels = 3;         // the radius, a half and a quarter of it
constexpr double kMinTypicalCount = 16;  // a level's disc holds at least about this many photons

struct RadiusLevels {
    std::vector<uint8_t> level;       // per photon of the map, index-aligned
    size_t count[kRadiusLevels] = {};  // photons per level
    double typical = 0.0;             // the typical effective number of photons in a box (diagnostics)
};

// The radius level of every photon of `photons` splatted with `radius` (render space is not needed: only
// differences of positions count). All level 0 where the radius or the map is empty. Parallel, deterministic.
RadiusLevels photon_radius_levels(const PhotonMap& photons, float radius, Stats& stats);

// Bytes photon_radius_levels holds at its peak for `photons` photons (its grid and counts).
double predict_radius_level_bytes(size_t photons);

// The radius of level k: radius / 2^k.
inline float level_radius(float radius, int level) { return radius / static_cast<float>(1u << level); }

}  // namespace ps
