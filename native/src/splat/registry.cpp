// The registry of splatting methods: the one list to extend when a method is added. Names are what the Python
// API, the Blender panel and the settings accept.
#include <string>

#include "photonsplat/errors.h"
#include "photonsplat/named_rows.h"
#include "photonsplat/settings.h"
#include "photonsplat/splatter.h"

namespace ps {

const std::vector<SplatMethodInfo>& splat_methods() {
    static const std::vector<SplatMethodInfo> methods = {
        {SplatMethod::brute, "brute", "Every photon against every view sample: the oracle, for small images", true,
         make_brute_splatter},
        {SplatMethod::tiled, "tiled", "Photons binned into 32×32-pixel screen tiles with per-tile depth bounds",
         true, make_tiled_splatter},
        {SplatMethod::cluster, "cluster", "The view-sample cluster hierarchy, culled by bounding boxes", true,
         make_cluster_splatter},
        {SplatMethod::cluster_cone, "cluster_cone",
         "The cluster hierarchy with normal-cone trivial reject and accept of whole clusters", true,
         make_cluster_cone_splatter},
        {SplatMethod::directional, "directional",
         "Approximate: photons stop at one hierarchy level and fill 8 direction bins per cluster", false,
         make_directional_splatter},
        {SplatMethod::gather, "gather", "Each view sample gathers photons from a hashed uniform grid", true,
         make_gather_splatter},
    };
    return methods;
}

const SplatMethodInfo& splat_method_info(SplatMethod method) {
    for (const SplatMethodInfo& m : splat_methods())
        if (m.method == method) return m;
    throw InvalidInput("method", "unknown splat method " + std::to_string(static_cast<int>(method)));
}

std::unique_ptr<Splatter> make_splatter(const RenderSettings& settings) {
    return splat_method_info(settings.method).make(settings);
}

const char* to_string(SplatMethod method) {
    for (const SplatMethodInfo& m : splat_methods())
        if (m.method == method) return m.name;
    return "unknown";
}

SplatMethod splat_method_from_string(const std::string& name) {
    return row_named(splat_methods(), name, "splat method").method;
}

std::vector<std::string> splat_method_names() {
    std::vector<std::string> names;
    for (const SplatMethodInfo& m : splat_methods()) names.emplace_back(m.name);
    return names;
}

}  // namespace ps
