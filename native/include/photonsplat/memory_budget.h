// The memory budget of a render: every large structure is predicted before it is allocated, and a render whose
// structures would not fit is refused with a message naming the structure, the overrun and the setting to lower.
// Predictions are upper bounds of what Stats::bytes later reports for the same structure (they are also written
// to Stats::predicted_bytes, so tests and docs can compare the two).
#pragma once
#include <cstdint>
#include <map>
#include <string>

#include "photonsplat/film.h"
#include "photonsplat/splatter.h"

namespace ps {

class Camera;
class Scene;
struct ClusterHierarchy;
struct RenderSettings;
struct Stats;

// What this process may use: the smaller of physical memory and the cgroup limit (containers, CI); 0 if unknown.
uint64_t available_memory_bytes();

// The budget used when RenderSettings::memory_budget is 0: three quarters of available_memory_bytes(), which
// leaves room for Blender, the scene itself and the OS. 0 (no check) when the memory size is unknown.
uint64_t default_memory_budget();

// Running account of the structures a render holds. reserve() is called BEFORE each allocation.
class MemoryBudget {
public:
    // limit = 0 means default_memory_budget().
    MemoryBudget(uint64_t limit, Stats& stats);

    // Records `bytes` under `structure` (in Stats::predicted_bytes) and throws InvalidInput(lower, ...) when the
    // structures held so far plus these bytes exceed the limit. `lower` names the setting that shrinks it.
    void reserve(const std::string& structure, double bytes, const std::string& lower);
    // A structure that is freed again (scratch buffers): counts against the limit only while it lives.
    void release(const std::string& structure);

    double limit() const { return limit_; }
    double held() const { return held_; }
    double remaining() const { return limit_ > held_ ? limit_ - held_ : 0.0; }

private:
    double limit_;
    double held_ = 0.0;
    Stats& stats_;
};

// Reserves, in the order a render allocates them, every structure whose size is known from the inputs alone:
// Embree's buffers, view samples, direct and indirect light, the photon map, the hierarchy (bounded by one leaf
// per pixel), the image; scratch buffers are reserved and released around their stage. Called before the render
// allocates anything, so a frame that cannot fit is refused at once.
void reserve_frame(MemoryBudget& budget, const Scene& scene, const Camera& camera, const RenderSettings& settings);

// A frame whose camera paths split at glass (view_samples.h) has more view samples than pixels: reserves what the
// samples beyond one a pixel add to every per-sample structure reserve_frame counted. Called once their number is
// known, right after the view samples stage (so their own bytes are counted just after they were allocated;
// they are at most one more sample a pixel for each part of a BSDF beyond the first), with the lobes of glossy
// samples, the buffer of light through rough transmission, the samples' shadow terminator lifts and the far sides
// of translucent surfaces (ViewSamples::far_side).
void reserve_split_samples(MemoryBudget& budget, const RenderSettings& settings, size_t pixels, size_t samples,
                           size_t lobes = 0, bool transmitted_direct = false, size_t terminator_lifts = 0,
                           size_t far_sides = 0);

// Refuses (InvalidInput, as reserve does) a frame that would not fit, before anything is allocated; for a caller
// that holds `extra_bytes_per_pixel` beside each pass's buffers (the progressive render's running sums).
void check_frame_memory(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        double extra_bytes_per_pixel);

// --- predictions, in bytes (each the structure as Stats::bytes names it) -----------------------------------

// View samples, one a pixel, with the per-pixel emission, alpha and first hit, and the scratch of their stage.
double predict_view_sample_bytes(int width, int height);
double predict_view_sample_scratch_bytes(int width, int height);
// Direct light and splatted indirect light per view sample; the film of these outputs with its scratch images.
double predict_per_sample_light_bytes(size_t samples);
// The boundary correction's coverage of each view sample (kernel_coverage.h); reserve_frame adds its index of
// each pixel's first sample.
double predict_kernel_coverage_bytes(size_t samples);
double predict_image_bytes(int width, int height, FilmOutputSet outputs);
// Embree's geometry buffers (the BVH itself lives in Embree and is not counted).
double predict_embree_bytes(const Scene& scene);
// The photon map: `emitted` paths × the expected number of stored photons per path, which Russian roulette bounds
// by the geometric series of the largest continuation probability of the scene's materials, × the
// growth slack of the per-chunk vectors (which hold the photons while they are traced).
double predict_photon_map_bytes(const Scene& scene, uint64_t emitted, int max_bounces);
// The hierarchy over `samples` view samples (at most one leaf per sample, at most 2 nodes per leaf); with cones
// the normal cones and node flags too.
double predict_hierarchy_bytes(size_t samples);
double predict_leaf_summary_bytes(size_t samples);  // directional: one summary per leaf
double predict_cone_bytes(size_t samples);

// Reserves the method's structures and returns the pair cap to use: the default cap, lowered so that the pair
// lists fit in what the budget has left. Refuses (naming `radius` and `resolution`) when not even a minimal cap
// fits.
uint64_t fit_pair_cap(MemoryBudget& budget, const SplatMemory& memory);

}  // namespace ps
