// What every splatting method shares: kernel names, input validation, and the coordinates photons are splatted in.
#include <cmath>
#include <limits>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/splat.h"

namespace ps {

const char* to_string(Kernel kernel) { return kernel == Kernel::uniform ? "uniform" : "epanechnikov"; }

Kernel kernel_from_string(const std::string& name) {
    if (name == "uniform") return Kernel::uniform;
    if (name == "epanechnikov") return Kernel::epanechnikov;
    throw InvalidInput("kernel", "'" + name + "' is not one of: uniform, epanechnikov");
}

void validate(const SplatParams& params, const PhotonMap& photons) {
    if (!(params.radius > 0.0f) || !std::isfinite(params.radius))
        throw InvalidInput("radius", std::to_string(params.radius) + " is not a positive finite number");
    if (!photons.photons.empty() && params.emitted == 0)
        throw InvalidInput("emitted", "0 emitted photons, but " + std::to_string(photons.photons.size()) +
                                          " stored: the estimate would divide by zero");
    if (params.directional_level < -1 || params.directional_level > 64)
        throw InvalidInput("directional_level", std::to_string(params.directional_level) + " is not in [-1, 64]");
    if (params.max_pairs_in_memory == 0)
        throw InvalidInput("max_pairs_in_memory", "0 leaves no room for a single (leaf, photon) pair; use >= 1");
}

void validate(const ClusterHierarchy& hierarchy, const ViewSamples& samples, const PhotonMap& photons) {
    if (hierarchy.sample_order.size() != samples.samples.size())
        throw InvalidInput("cluster hierarchy", "built over " + std::to_string(hierarchy.sample_order.size()) +
                                                    " view samples, but " + std::to_string(samples.samples.size()) +
                                                    " were given");
    if (photons.photons.size() >= std::numeric_limits<uint32_t>::max())
        throw InvalidInput("photons", "too many photons for 32-bit photon indices");
}

// A float subtraction is already the exactly rounded difference, so doing it in double would not help.
std::vector<glm::vec3> relative_photon_positions(const PhotonMap& photons, const glm::vec3& origin) {
    std::vector<glm::vec3> relative(photons.photons.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, relative.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) relative[i] = photons.photons[i].position - origin;
    });
    return relative;
}

}  // namespace ps
