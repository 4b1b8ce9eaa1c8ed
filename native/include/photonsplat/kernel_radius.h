// The kernel radius used when the user leaves it at 0 (automatic).
//
// Two limits decide it. Noise: a disc should hold about the same number of photons whatever their count, so the
// radius starts from a fraction of the scene's size that shrinks as 1/sqrt(photons) (default_radius). Bias: a
// kernel disc that reaches past the edge of the surface it sits on (a corner, a column, a thin ledge) finds no
// photons there and darkens the surface near its edges (boundary bias). The scene's size says nothing about how
// far apart those edges are: an atrium of 0.28 m columns and a Cornell box can have the same diagonal. So the
// automatic radius is the one of default_radius × 1, 1/√2, 1/2, 1/(2√2), 1/4 that balances the two best: the
// expected boundary loss over what the camera sees (boundary_loss) squared, plus a disc's photon variance.
#pragma once
#include <cstdint>

#include "photonsplat/camera.h"

namespace ps {

class Scene;

// About 1.5 % of the scene's diagonal at 200k photons, shrinking as 1/sqrt(photons).
float default_radius(const Scene& scene, uint64_t photons);

// The expected fraction of a kernel disc of radius `radius` that finds no surface like the one it is centred on,
// averaged over the surfaces a grid of camera rays sees first (a 0..1 figure; 0 for a plane wider than the
// disc). A disc around a point x with normal n is probed at fixed points of the tangent disc, each by a ray
// along −n through the kernel's sphere: a probe counts as covered when that ray meets a non-specular surface
// facing within 60° of n (the splat kernel's own normal test). The points are the first hits of camera rays
// through the pixel positions ((i + 0.5)·width/columns, (j + 0.5)·height/rows), with kBoundaryLossGrid columns
// or rows across the image's longer side (fewer where the image has fewer pixels). Deterministic; 8 probes a
// point. 0 when the camera sees no diffuse or glossy surface.
constexpr int kBoundaryLossGrid = 32;
float boundary_loss(const Scene& scene, const Camera& camera, float radius);

// default_radius, or a smaller one (a quarter at most) where the boundary bias of what the camera sees calls
// for it: the first radius of progressive renders that the boundary correction (kernel_coverage.h) does not
// cover, whose passes average away the extra noise (a one-pass render, or one with the correction, keeps
// default_radius: render.h). Deterministic; `camera` may be in world or render space.
float automatic_radius(const Scene& scene, const Camera& camera, uint64_t photons);

}  // namespace ps
