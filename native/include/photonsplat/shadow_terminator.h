#pragma once
// Cycles' shadow terminator geometry offset (Object > Shading > Shadow Terminator > Geometry Offset, 0.1 by
// default in Blender): a shadow ray from a smooth-shaded triangle, towards a light near the triangle's own
// horizon, starts on the smooth surface the vertex normals describe instead of on the flat triangle. A
// low-poly sphere is then lit up to where its shading normals turn from the light, not only to where its facets
// do; without it, Cycles' light samples there would meet the facet itself (the faceted "terminator").
//
// Cycles 3.4: light/sample.h, shadow_ray_smooth_surface_offset (the lift: a parabolic estimate of the smooth
// surface's height over the triangle, bounded by the corners' tangent planes) and shadow_ray_offset (how much of
// it a light direction takes). Only next-event estimation's shadow rays take it, as in Cycles; photons meet the
// flat triangles.

#include <glm/vec3.hpp>

namespace ps {

class Scene;
struct SurfacePoint;

// The lift of a surface point's shadow rays towards one side of its surface, in render space, and its object's
// Geometry Offset (0: none).
struct TerminatorLift {
    glm::vec3 lift{0.0f};
    float cutoff = 0.0f;
};

// The lift at s for light arriving on the side of `side` (s's geometric normal, or its negation for light
// through the surface). Zero where the instance has no offset or the mesh no shading normals; zero too on a
// flat-shaded triangle (its corner normals are its own), as Cycles does for faces that are not smooth.
TerminatorLift terminator_lift(const Scene& scene, const SurfacePoint& s, const glm::vec3& side);

// Where a shadow ray from x towards wi starts (before offset_ray_origin): x lifted by the share of `t` that
// Cycles gives this direction. n: the shading normal; side: the geometric normal on the light's side. The share
// is 1 within `cutoff` of the triangle's horizon (n·wi or side·wi below it), falling to 0 at twice that.
glm::vec3 terminator_origin(const glm::vec3& x, const TerminatorLift& t, const glm::vec3& n, const glm::vec3& side,
                            const glm::vec3& wi);

// Whether a light sample from wi below the triangle's horizon (side·wi <= 0) but above the shading normal's is
// one Cycles traces (from the lifted point, where its own triangle may still block it) instead of dropping.
bool terminator_reaches_below(const TerminatorLift& t, const glm::vec3& n, const glm::vec3& side, const glm::vec3& wi);

}  // namespace ps
