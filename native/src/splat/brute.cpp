// The oracle: every photon against every view sample. O(photons × samples), for small images and for tests;
// every exact method must reproduce its output.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/errors.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/splatter.h"

namespace ps {
namespace {

// One sample against a million photons takes milliseconds; polling between photon blocks keeps a cancel
// prompt even then, and costs one relaxed atomic load per block.
constexpr size_t kPhotonsPerCancelCheck = 1 << 16;

}  // namespace

std::vector<glm::vec3> splat_brute(const ViewSamples& samples, const PhotonMap& photons, const SplatParams& params,
                                   const RenderControl& control, Stats& stats) {
    validate(params, photons);
    control.check();
    const std::vector<ViewSample>& views = samples.samples;
    std::vector<glm::vec3> radiance(views.size(), glm::vec3(0.0f));
    double& tests_counter = stats.counters["photon_sample_tests"];
    double& contributing_counter = stats.counters["contributing_pairs"];
    if (views.empty() || photons.photons.empty()) return radiance;  // (emitted may be 0: nothing to finish)

    const std::vector<glm::vec3> positions = relative_photon_positions(photons, samples.origin);
    const size_t photon_count = positions.size();
    std::atomic<uint64_t> tests{0}, contributing{0}, samples_done{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, views.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
        uint64_t local_contributing = 0;
        for (size_t i = range.begin(); i != range.end(); ++i) {
            const ViewSample& s = views[i];
            glm::dvec3 reflected_flux(0.0);
            for (size_t begin = 0; begin < photon_count; begin += kPhotonsPerCancelCheck) {
                control.check();
                const size_t end = std::min(photon_count, begin + kPhotonsPerCancelCheck);
                for (size_t j = begin; j != end; ++j) {
                    if (!photon_reaches_sample(s, positions[j], photons.photons[j], params)) continue;
                    reflected_flux += photon_reflected_flux(s, samples.lobes.data(), positions[j], photons.photons[j], params);
                    ++local_contributing;
                }
            }
            radiance[i] = finish_sample(s, reflected_flux, params);
        }
        tests += uint64_t(range.size()) * photon_count;
        contributing += local_contributing;
        control.advance(samples_done += range.size(), views.size());
    });
    tests_counter += double(tests.load());
    contributing_counter += double(contributing.load());
    return radiance;
}

namespace {

class BruteSplatter final : public SampleSplatter {
public:
    BruteSplatter() : SampleSplatter(splat_brute) {}
    SplatMemory predict_memory(const SplatFrame&, size_t photons, const SplatParams&) const override {
        SplatMemory m;
        m.fixed["photon_positions"] = photon_position_bytes(photons);
        return m;
    }
};

}  // namespace

std::unique_ptr<Splatter> make_brute_splatter(const RenderSettings&) { return std::make_unique<BruteSplatter>(); }

}  // namespace ps
