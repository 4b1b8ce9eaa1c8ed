// Stage 1 of the pipeline: a camera ray per pixel, followed through mirrors, glass and rough transmission to the
// surfaces that keep it: a view sample holds a surface's reflection parts (shading.h), what photons are later
// splatted onto (and at translucency, its far side, for the caustic photons there). At the first surface with more
// than one part (the reflection lobes, a mirror, a refraction, transparency, a rough transmission, translucency)
// the path is split once: each part ends in a view sample of its own, weighted by the part (glass: the refracted
// and the reflected path, weighted by Fresnel), so a pixel has one sample or a few.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/camera.h"
#include "photonsplat/closures.h"
#include "photonsplat/shadow_terminator.h"

namespace ps {

class Scene;
class RenderControl;
struct Stats;

enum ViewSampleFlags : uint32_t {
    kViaSpecular = 1u,  // the camera path bounced off a mirror, through glass or a rough transmission before it
    kGlossy = 2u,       // the surface has lobes beyond Lambert's (shading.h): its BRDF depends on the directions
    // Everything the sample gathers is what Cycles' Caustics toggles remove, which drop a glossy, mirror or
    // refracting closure met right after a diffuse-labelled scatter (a translucent one, on camera paths): the path
    // met such a part after translucency, or the sample's own surface, reached right after translucency, has no
    // diffuse part. The Caustics output holds its direct and indirect light whole.
    kCausticSample = 4u,
    kInsideSample = 8u, // on the back face of a transmitting surface (inside glass): receives kInsidePhoton photons only
    // The shading normal is not the interpolated one (smooth_normal): its diffuse parts take Cycles' bump
    // shadowing term of each photon's direction (bump_shadowing.h).
    kBumpShadowed = 16u,
    // Which term (bump_shadowing.h): with neither bit, Cycles 3.x's.
    kBumpShadowingCycles4 = 32u,
    kBumpUncorrected = 64u,  // with kBumpShadowingCycles4: the material's Bump Map Correction is off
    // The camera path reached the sample right after a diffuse-labelled scatter (translucency) and its surface has
    // a diffuse part (without one it is a kCausticSample). Cycles' Caustics toggles drop the surface's other parts
    // there: what those gather, direct light included, is the Caustics output's whole, and the diffuse parts keep
    // only their photons' kReachedDiffusely share (splat.h: sample_brdf; render.cpp: splat_caustics).
    kAfterDiffuseScatter = 128u,
};

// The flags that record a bump shadowing term's form, and the form they record.
inline uint32_t bump_form_flags(BumpShadowing form) {
    return form == BumpShadowing::cycles3 ? 0u
           : form == BumpShadowing::cycles4 ? uint32_t(kBumpShadowingCycles4)
                                            : uint32_t(kBumpShadowingCycles4) | uint32_t(kBumpUncorrected);
}
inline BumpShadowing bump_form_of(uint32_t flags) {
    if (!(flags & kBumpShadowingCycles4)) return BumpShadowing::cycles3;
    return flags & kBumpUncorrected ? BumpShadowing::cycles4_uncorrected : BumpShadowing::cycles4;
}

// Bits 8–15 of ViewSample::flags: which branch of its pixel's camera path a sample ends (0 for the path that
// stayed; the first hit's other parts each start a branch), so that each sample draws its own random numbers.
constexpr uint32_t kBranchShift = 8;
constexpr uint32_t kBranchMask = 0xffu << kBranchShift;
inline uint32_t branch_of(uint32_t flags) { return (flags & kBranchMask) >> kBranchShift; }

struct ViewSample {
    glm::vec3 position;        // RELATIVE TO ViewSamples::origin (camera-relative: keeps precision far from 0)
    glm::vec3 normal;          // geometric normal, flipped to face the arriving camera path
    glm::vec3 shading_normal;  // the closures' normal (SurfacePoint::shading_normal), on the same side as `normal`
    glm::vec3 smooth_normal;   // kBumpShadowed samples: the interpolated one (Cycles' sd->N), on the same side
    glm::vec3 wo;              // unit direction back along the camera path
    glm::vec3 albedo;          // Σ of the Lambert closures' weights: that part of the BRDF is albedo / π
    glm::vec3 throughput;      // product of specular weights along the camera path (1 for a direct hit); a pixel's
                               // radiance is the sum over its samples of throughput × what reaches the sample
    uint32_t pixel;            // y * width + x, y = 0 at the top
    uint32_t flags;            // ViewSampleFlags
    float depth;               // view depth of the FIRST hit of the pixel's camera ray (for cluster keys)
    float rounding_scale;      // SurfacePoint::rounding_scale, for rays leaving the sample (offset_ray_origin)
    uint32_t lobe_begin;       // kGlossy samples: its other reflection lobes are ViewSamples::lobes[lobe_begin, +count)
    uint16_t lobe_count;
    // Narrow lobes (shading.h: narrow_lobe_branches) right after those: the sample's direct light evaluates them,
    // its splat does not (the camera path followed them as a branch of its own).
    uint16_t branched_lobes;
    // Cycles' defensive floor of the parts' sampling weights at the camera's first hit (defensive_floor in
    // shading.h; 0 elsewhere): how Cycles labels the scatter here, for the Caustics output (LabelShare).
    float selection_floor;
};

// A kAfterDiffuseScatter sample with parts Cycles' Caustics toggles drop (lobes beyond its Lambert albedo; those
// labelled diffuse drop nothing, but few samples are such): the Caustics output takes their light whole.
inline bool has_dropped_parts(const ViewSample& s) {
    return (s.flags & kAfterDiffuseScatter) && (s.lobe_count > 0 || s.branched_lobes > 0);
}

struct ViewSamples {
    int width = 0, height = 0;
    glm::vec3 origin{0.0f};             // render-space position (scene.h) sample positions are relative to (the camera)
    std::vector<ViewSample> samples;    // in pixel order; none where the camera path escaped, was cut out or was
                                        // dropped, else one per part of the first hit's BSDF that ends in a sample
                                        // (shading.h: its lobes, its mirror, refraction, transparency, transmission)
    std::vector<Lobe> lobes;            // the reflection lobes of kGlossy samples (beyond the Lambert albedo)
    // The far sides of the translucent surfaces camera paths scattered through, in pixel order: Lambert samples of
    // the translucent albedo facing away from the path, which gather only the caustic photons stored on that side
    // (render.cpp), what the path drops (view_samples.cpp: add_far_side_sample). No direct light, no lobes.
    std::vector<ViewSample> far_side;
    // The lift of the shadow rays of the samples that have one (shadow_terminator.h: on a smooth triangle of an
    // instance with a terminator offset), by sample index, in increasing order; empty where none has.
    struct SampleLift {
        uint32_t sample;
        TerminatorLift lift;
    };
    std::vector<SampleLift> terminator;
    // width × height, only where the scene has rough transmission or translucency, or a near-mirror (a Cycles 3.x
    // Multiscatter GGX near roughness 0.02), else empty: light that reached camera paths through such a surface
    // from the lights directly (its own next-event estimation), or that a near-mirror's light samples found
    // (near_mirror_light).
    std::vector<glm::vec3> transmitted_direct;
    // width × height, only where transmitted_direct is: the part of emission, background, lights and
    // transmitted_direct that camera paths found beyond translucency and a glossy, mirror or refracting part
    // (kCausticSample's rule). Already in those; the Caustics output holds it too.
    std::vector<glm::vec3> caustic_emission;
    std::vector<glm::vec3> emission;    // width × height: emission and background seen along camera paths
    std::vector<float> alpha;           // width × height: 1 where a camera ray hit geometry, else 0
    // Of the FIRST surface each camera ray hits (glass and mirrors included), as Cycles' Normal and Depth passes:
    std::vector<glm::vec3> first_normal;  // width × height: world-space shading normal facing the camera; 0 if none
    std::vector<float> first_depth;       // width × height: view depth along the camera axis; 0 if the ray escaped

    size_t bytes() const;
};

struct ViewSampleSettings {
    uint64_t seed = 0;
    int max_specular_depth = 8;   // bounces through mirror/glass before the path is dropped
    // false: every ray through its pixel's centre (a one-shot render). true: through point `pass` − 1 of the
    // pixel's low-discrepancy sequence (SampleSequence(sequence_seed, pixel, kPixelStream)); progressive passes
    // after the first use it, so their mean is box-filtered over each pixel (anti-aliasing), and a glint covering
    // part of a pixel converges as Cycles' samples place it, not at the 1/√N of independent positions.
    bool jitter = false;
    uint64_t sequence_seed = 0;  // the render's own seed: one sequence per pixel across its passes
    uint32_t pass = 0;           // the progressive iteration (≥ 1 where jitter is on)
    // Follow every part of the BSDF at a camera path's first surface (the view sample of its lobes, the mirror,
    // the refraction, transparency, the rough transmission: a sample each), instead of one chosen with its
    // weight's probability. Later surfaces always choose one.
    bool split_at_glass = true;
    int samples_per_light = 4;    // next-event estimation at rough transmissions along camera paths
};

ViewSamples generate_view_samples(const Scene& scene, const Camera& camera, const ViewSampleSettings& settings,
                                  const RenderControl& control, Stats& stats);

}  // namespace ps
