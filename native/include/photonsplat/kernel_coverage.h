// Boundary-bias correction of the density estimate. The splat divides the photons' flux in a kernel ball by
// π r², the area a plane through the ball's centre has inside it. Near the edge of a surface (a corner, a
// column, a ledge) less like-facing surface lies inside the ball, so fewer photons land there and the estimate
// is darker by that missing area. kernel_coverage measures, for every view sample, the kernel-weighted area of
// photon-receiving surface inside its ball over π r² (its coverage), so that the splatted radiance can be
// divided by it. Where the irradiance is locally constant this removes the edge's bias; as the radius shrinks
// the coverage goes to 1 almost everywhere, so the estimate stays consistent.
#pragma once
#include <cstdint>
#include <vector>

#include "photonsplat/splat.h"

namespace ps {

class Scene;  // (splat.h declares the samples, the control and the stats)

// Probes of each view sample's disc, and the smallest coverage divided by: a sample whose disc is almost all
// off its surface (a baluster seen side-on under a metre-wide kernel) is brightened 4× at most, which keeps the
// few photons such a disc holds from turning into speckles.
constexpr int kCoverageProbes = 8;
constexpr float kMinCoverage = 0.25f;

// Per view sample (index-aligned with samples.samples), its coverage, in [kMinCoverage, 2]: 1 for a plane
// through the centre, about 1 for a sphere (a ball centred on a sphere holds π r² of it), less near edges, up
// to 2 where surfaces tilted by the normal tolerance fill the ball. Each probe point of the tangent disc is
// tested by a ray along −n through the kernel's ball: the first non-specular surface it meets counts if it
// faces within the splat's normal tolerance of the sample's normal, with the area it stands for (over the
// cosine of its tilt) and the kernel's weight at its distance. A probe that finds the sample's own plane going
// on counts only if the sample reaches the probe's column (the segment from the sample to it crosses no surface
// photons land on): the floor behind a wall standing on it lies in the wall's shadow, not in the light of the
// floor in front. Mirrors and glass are passed through (photons land on what lies behind them).
// Glossy parts keep their estimate: a sample's coverage c is taken as 1 − (1 − c) d, d its diffuse-like share
// (kernel_coverage.cpp says why). One probe pattern, drawn from (seed, kernel_coverage), serves every sample.
// Multi-threaded, deterministic for a seed. With `wanted` (index-aligned with samples.samples), only the samples
// it marks are measured and the others keep 1: a radius level's light (photon_density.h) reaches few samples, and
// a small radius blends few grid pixels, so measuring all would cost several times the whole frame's correction.
std::vector<float> kernel_coverage(const Scene& scene, const ViewSamples& samples, const SplatParams& params,
                                   uint64_t seed, const RenderControl& control, Stats& stats,
                                   const std::vector<uint8_t>* wanted = nullptr);

}  // namespace ps
