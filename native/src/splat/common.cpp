// What every splatting method shares: method names, input validation, and the coordinates photons are splatted in.
#include <cmath>
#include <limits>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/splat.h"

namespace ps {
namespace {

// Every method and its name; the one list to extend when a method is added.
struct MethodName {
    SplatMethod method;
    const char* name;
};
constexpr MethodName kMethodNames[] = {
    {SplatMethod::brute, "brute"},
    {SplatMethod::tiled, "tiled"},
    {SplatMethod::cluster, "cluster"},
    {SplatMethod::cluster_cone, "cluster_cone"},
    {SplatMethod::directional, "directional"},
    {SplatMethod::gather, "gather"},
};

}  // namespace

const char* to_string(SplatMethod method) {
    for (const MethodName& m : kMethodNames)
        if (m.method == method) return m.name;
    return "unknown";
}

SplatMethod splat_method_from_string(const std::string& name) {
    std::string known;
    for (const MethodName& m : kMethodNames) {
        if (name == m.name) return m.method;
        known += known.empty() ? m.name : std::string(", ") + m.name;
    }
    throw InvalidInput("splat method", "'" + name + "' is not one of: " + known);
}

std::vector<std::string> splat_method_names() {
    std::vector<std::string> names;
    for (const MethodName& m : kMethodNames) names.emplace_back(m.name);
    return names;
}

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
