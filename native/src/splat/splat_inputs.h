// What the workers of the cluster, directional and tiled splats read and where they report, held as their base:
// the view samples, the photons with their positions relative to the samples' origin, the parameters, the control
// polled for cancels, and the stats.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/photons.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"

namespace ps {

class SplatInputs {
protected:
    SplatInputs(const ViewSamples& samples, const PhotonMap& photons, const SplatParams& params,
                const RenderControl& control, Stats& stats)
        : views_(samples.samples),
          lobes_(samples.lobes.data()),
          photons_(photons.photons),
          params_(params),
          control_(control),
          stats_(stats),
          positions_(relative_photon_positions(photons, samples.origin)) {}

    // What a splat that holds its (leaf or tile, photon) pairs in batches reports: counters "<unit>_photon_pairs"
    // and "splat_batches", bytes "<unit>_photon_lists" (their peak) and "splat_sample_sums" (kept between batches).
    void report_batches(const std::string& unit, uint64_t pairs, uint64_t batches, double peak_list_bytes,
                        double sum_bytes) {
        stats_.counters[unit + "_photon_pairs"] += double(pairs);
        stats_.counters["splat_batches"] += double(batches);
        stats_.bytes[unit + "_photon_lists"] = peak_list_bytes;
        stats_.bytes["splat_sample_sums"] = sum_bytes;
    }

    const std::vector<ViewSample>& views_;
    const Lobe* lobes_;  // ViewSamples::lobes, for sample_brdf
    const std::vector<Photon>& photons_;
    const SplatParams& params_;
    const RenderControl& control_;
    Stats& stats_;
    const std::vector<glm::vec3> positions_;
};

}  // namespace ps
