// The seam between the pipeline and a splatting method (stages 5–6). A method is a Splatter: it says which
// cluster hierarchy it splats onto (if any), predicts the memory of its own structures, and splats a photon set
// onto the view samples, returning the indirect radiance of every sample with what kind of estimate it is.
// The registry lists every method with its name and whether it is exact; render.cpp, memory_budget.cpp and
// progressive.cpp only ever talk to a method through these, so a method's special cases live in its own file.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/hierarchy.h"
#include "photonsplat/splat.h"

namespace ps {

class Camera;
class RenderControl;
struct RenderSettings;
struct Stats;

// What one iteration of the pipeline hands a method: the view samples and, when the method asked for one, the
// hierarchy built over them.
struct SplatFrame {
    const ViewSamples& samples;
    const Camera& camera;                          // render space, as the samples
    const ClusterHierarchy* hierarchy = nullptr;   // built with Splatter::hierarchy_options(); null when none
    uint32_t iteration = 0;                        // progressive iteration; 0 = the one-shot render
    int threads = 1;                               // workers of the render's arena (per-thread buffers)
};

// What a splat gives back.
struct SplatEstimate {
    std::vector<glm::vec3> radiance;  // indirect radiance per view sample, index-aligned with frame.samples
    // Each sample's value is the kernel estimate over the photons within r of it, the estimate brute computes.
    // False for an approximation that gathers photons some other way (directional's per-cluster blocks): the
    // boundary correction, which rescales a kernel estimate, then does not apply.
    bool kernel_estimate = true;
};

// The structures of one splat, known once the view samples, photons and hierarchy exist. Pair lists are bounded
// by SplatParams::max_pairs_in_memory, which fit_pair_cap() (memory_budget.h) chooses so that they fit.
struct SplatMemory {
    std::map<std::string, double> fixed;  // Stats::bytes key → bytes of structures whose size is known
    std::string pair_key;                 // Stats::bytes key of the pair lists; empty for methods without pairs
    double pair_fixed = 0.0;              // the pair lists' bookkeeping (offsets, counts)
    double per_pair = 0.0;                // bytes per (leaf or tile, photon) pair at the peak
};

// Bytes a (leaf or tile, photon) pair takes at the peak of the cluster and tiled splats: 4 in the traversal or
// binning buffers, 4 in the sorted lists, and the growth slack of the buffers.
constexpr double kPairBytesAtPeak = 9.0;
// Photon positions relative to the samples' origin, which every method makes.
inline double photon_position_bytes(size_t photons) { return double(photons) * double(sizeof(glm::vec3)); }
// Per-sample double sums that batched splats keep between batches.
inline double sample_sum_bytes(size_t samples) { return double(samples) * double(sizeof(glm::dvec3)); }
// The cluster splat's structures (positions, sums, per-leaf pair lists); directional falls back to that splat.
SplatMemory cluster_splat_memory(const SplatFrame& frame, size_t photons);

class Splatter {
public:
    virtual ~Splatter() = default;

    // The cluster hierarchy this method splats onto and the extras it needs (normal cones, leaf summaries);
    // nothing for methods that work on the samples directly.
    virtual std::optional<ClusterBuildOptions> hierarchy_options() const { return std::nullopt; }

    // Bytes of the method's own structures for this frame and photon count (params: kernel and radius).
    virtual SplatMemory predict_memory(const SplatFrame& frame, size_t photons, const SplatParams& params) const = 0;

    // The indirect radiance every view sample receives from `photons`. An iteration calls it once per photon set
    // it splats (the photons of each radius level, photon_density.h, and of each the caustic photons alone when
    // the caustics output is asked for), with the same frame; the params differ only in their radius, never
    // above the first call's. Throws InvalidInput, Cancelled.
    virtual SplatEstimate splat(const SplatFrame& frame, const PhotonMap& photons, const SplatParams& params,
                                const RenderControl& control, Stats& stats) const = 0;
};

// A method that splats the view samples directly, without a hierarchy or the camera (brute, gather): its splat is
// a function of the samples and the photons, and always a kernel estimate.
class SampleSplatter : public Splatter {
public:
    using Function = std::vector<glm::vec3> (*)(const ViewSamples&, const PhotonMap&, const SplatParams&,
                                                const RenderControl&, Stats&);
    explicit SampleSplatter(Function function) : function_(function) {}
    SplatEstimate splat(const SplatFrame& frame, const PhotonMap& photons, const SplatParams& params,
                        const RenderControl& control, Stats& stats) const override {
        return {function_(frame.samples, photons, params, control, stats)};
    }

private:
    Function function_;
};

// The registry: every method, in the order UIs list them.
struct SplatMethodInfo {
    SplatMethod method;
    const char* name;
    const char* description;  // one line, for UIs and help texts
    bool exact;               // the same photons give brute's image, up to float summation order
    std::unique_ptr<Splatter> (*make)(const RenderSettings& settings);  // the method's own settings are read here
};
const std::vector<SplatMethodInfo>& splat_methods();
const SplatMethodInfo& splat_method_info(SplatMethod method);
// The splatter of settings.method, configured by the settings it reads.
std::unique_ptr<Splatter> make_splatter(const RenderSettings& settings);

// Each method's factory, defined in its own file (splat/*.cpp) and listed by the registry (splat/registry.cpp).
std::unique_ptr<Splatter> make_brute_splatter(const RenderSettings& settings);
std::unique_ptr<Splatter> make_tiled_splatter(const RenderSettings& settings);
std::unique_ptr<Splatter> make_cluster_splatter(const RenderSettings& settings);
std::unique_ptr<Splatter> make_cluster_cone_splatter(const RenderSettings& settings);
std::unique_ptr<Splatter> make_directional_splatter(const RenderSettings& settings);
std::unique_ptr<Splatter> make_gather_splatter(const RenderSettings& settings);

}  // namespace ps
