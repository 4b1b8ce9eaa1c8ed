// The settings of a render, and the rules every one of them must satisfy.
#pragma once
#include <cstdint>

#include "photonsplat/film.h"
#include "photonsplat/splat.h"

namespace ps {

struct RenderSettings {
    uint64_t photons = 200000;        // photon paths emitted
    float radius = 0.0f;              // kernel radius in world units; 0 = derived from the scene's size
    SplatMethod method = SplatMethod::cluster_cone;
    int max_bounces = 8;              // photon path length bound, and camera-path specular depth bound
    uint64_t seed = 0;
    int threads = 0;                  // 0 = all cores
    int direct_samples = 4;           // shadow rays per light per view sample (soft shadows)
    float normal_tolerance = 60.0f;   // τ in degrees: photons on surfaces turned further away are ignored
    float plane_distance = 0.0f;      // κ of the plane-distance test (stacked surfaces); 0 = off
    Kernel kernel = Kernel::uniform;  // density-estimation kernel
    // Divide each view sample's splatted light by the part of its kernel disc that lies on a like-facing surface
    // (kernel_coverage.h): removes the darkening of corners, edges and thin parts (boundary bias). Every method
    // but directional, whose blocks are not kernel discs (it is corrected where it falls back to exact).
    bool boundary_correction = true;
    int directional_level = -1;       // directional method: hierarchy level from the leaves; -1 = from the radius
    uint64_t memory_budget = 0;       // bytes the render may hold; 0 = 3/4 of available memory (memory_budget.h)
    bool guide_photons = true;        // emit sun photons where pilot paths found them stored (emission_guide.h)
    // Extra photons per pass aimed at mirror and glass objects from point, spot and area lights, as a fraction
    // of `photons`; they only add caustic photons (caustic_aim.h). 0 = off; nothing is added without mirrors
    // or glass.
    float aimed_photons = 0.1f;
    // The film outputs the render produces (film.h; combined always). Fewer outputs hold less memory, above all in
    // a progressive render's running sums.
    FilmOutputSet outputs = kDefaultFilmOutputs;
    bool caustics_pass = false;       // also produce the caustics output: the caustic photons (L S+ D) splatted alone
    bool transparent = false;         // film transparency: alpha 0 and no background where camera rays escape
    // Progressive rendering (progressive.h): passes of new photons, jittered camera rays and a shrinking radius,
    // averaged. 1 = the paper's one-shot method, exactly the image of a single pass.
    uint32_t iterations = 1;              // 0 = no pass limit (then time_limit must be > 0)
    double time_limit = 0.0;          // seconds of rendering; 0 = none. A pass predicted to end past it is not started
    float alpha = 2.0f / 3.0f;        // Knaus & Zwicker: r_i² = r_{i−1}²·(i−1+α)/i; in (0, 1], 1 = fixed radius
};

void validate(const RenderSettings& settings);  // throws InvalidInput naming the field

// The outputs a render with these settings fills: settings.outputs, combined, and caustics with caustics_pass.
FilmOutputSet requested_outputs(const RenderSettings& settings);

}  // namespace ps
