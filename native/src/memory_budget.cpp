#include "photonsplat/memory_budget.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/photons.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"

namespace ps {

namespace {

std::string size_text(double bytes) {
    char text[48];
    if (bytes >= 1024.0 * 1024.0 * 1024.0)
        std::snprintf(text, sizeof text, "%.2f GiB", bytes / (1024.0 * 1024.0 * 1024.0));
    else
        std::snprintf(text, sizeof text, "%.1f MiB", bytes / (1024.0 * 1024.0));
    return text;
}

// cgroup v2 (and v1) limits of this process's memory: what the OOM killer enforces inside a container.
uint64_t cgroup_limit() {
    for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
        std::ifstream in(path);
        std::string text;
        if (in >> text && !text.empty() && text != "max") {
            try {
                return std::stoull(text);
            } catch (...) {
            }
        }
    }
    return 0;
}

// Bytes a pair takes at the peak in the cluster and tiled splats: 4 in the traversal/binning buffers, 4 in the
// sorted lists, and the growth slack of the buffers (see cluster.cpp and tiled.cpp).
constexpr double kBytesPerPair = 9.0;
// The cap never goes below this many pairs: below it the splat would run in thousands of batches.
constexpr uint64_t kMinPairCap = uint64_t(1) << 20;

// The methods that splat onto the view-sample cluster hierarchy (tiled, gather and brute do not build it).
bool builds_hierarchy(SplatMethod method) {
    return method == SplatMethod::cluster || method == SplatMethod::cluster_cone || method == SplatMethod::directional;
}

}  // namespace

uint64_t available_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    uint64_t memory = (pages > 0 && page > 0) ? uint64_t(pages) * uint64_t(page) : 0;
    const uint64_t limit = cgroup_limit();
    if (limit > 0 && (memory == 0 || limit < memory)) memory = limit;
    return memory;
}

uint64_t default_memory_budget() { return available_memory_bytes() / 4 * 3; }

MemoryBudget::MemoryBudget(uint64_t limit, Stats& stats)
    : limit_(static_cast<double>(limit > 0 ? limit : default_memory_budget())), stats_(stats) {
    stats_.values["memory_budget"] = limit_;
}

void MemoryBudget::reserve(const std::string& structure, double bytes, const std::string& lower) {
    stats_.predicted_bytes[structure] += bytes;
    const double total = held_ + bytes;
    if (limit_ > 0.0 && total > limit_) {
        throw InvalidInput(lower, structure + " would need about " + size_text(bytes) + ", taking the render to " +
                                      size_text(total) + ": " + size_text(total - limit_) +
                                      " over the memory budget of " + size_text(limit_) +
                                      " (memory_budget; 0 = 3/4 of this machine's " +
                                      size_text(double(available_memory_bytes())) + "); lower " + lower +
                                      ", or raise memory_budget");
    }
    held_ = total;
}

void MemoryBudget::release(const std::string& structure) {
    const auto it = stats_.predicted_bytes.find(structure);
    if (it != stats_.predicted_bytes.end()) held_ = std::max(0.0, held_ - it->second);
}

double predict_view_sample_bytes(int width, int height) {
    const double pixels = double(width) * double(height);
    // a sample, emission, alpha, first hit's normal and depth
    return pixels * double(sizeof(ViewSample) + 2 * sizeof(glm::vec3) + 2 * sizeof(float));
}

double predict_view_sample_scratch_bytes(int width, int height) {
    return double(width) * double(height) * double(sizeof(ViewSample));  // the bands' samples before they are joined
}

double predict_per_sample_light_bytes(size_t samples) { return double(samples) * double(sizeof(glm::vec3)); }

double predict_kernel_coverage_bytes(size_t samples) { return double(samples) * double(sizeof(float)); }

double predict_image_bytes(int width, int height, bool caustics_pass) {
    // RGBA, emission, direct, indirect, normal, depth (+ caustics)
    const double floats = 4 + 3 * 3 + 3 + 1 + (caustics_pass ? 3 : 0);
    return double(width) * double(height) * floats * sizeof(float);
}

double predict_embree_bytes(const Scene& scene) {
    // Each mesh's vertex and index buffers (shared with Embree), and per instance a transform and a top-level node.
    double bytes = 0.0;
    for (const MeshData& mesh : scene.meshes())
        bytes += double(mesh.positions.size()) * 3 * sizeof(float) + double(mesh.triangle_count()) * 3 * sizeof(unsigned);
    return bytes + double(scene.instances().size()) * double(sizeof(glm::mat4) + 64);
}

double predict_photon_map_bytes(const Scene& scene, uint64_t emitted, int max_bounces) {
    if (emitted == 0 || scene.triangle_count() == 0) return 0.0;  // photons are stored only on geometry
    // A photon is stored at non-specular vertices after the first; after a non-specular vertex it goes on with
    // probability at most `a` (Russian roulette on the albedo; a glossy lobe's F·G1 may reach 1).
    double a = 0.0;
    bool specular = false;
    for (const Material& m : scene.materials()) {
        if (m.is_specular())
            specular = true;
        else
            a = std::max(a, m.is_glossy() ? 1.0 : double(std::max({m.color.x, m.color.y, m.color.z})));
    }
    a = std::min(a, 1.0);
    const double bounces = double(std::max(max_bounces, 0));
    // Expected non-specular vertices stored: a + a² + ... (first vertex non-specular), or 1 + a + ... when a
    // specular first hit may carry the photon on; never more than max_bounces.
    const double series = a >= 1.0 ? bounces : (specular ? 1.0 : a) / (1.0 - a);
    const double per_path = std::min(bounces, series);
    // The expectation plus a margin for the spread of a small count (a few paths may store max_bounces each).
    const double stored = double(emitted) * per_path + 16.0 * bounces;
    return stored * double(sizeof(Photon));
}

double predict_hierarchy_bytes(size_t samples) {
    const double s = double(samples);
    return 2.0 * s * double(sizeof(ClusterNode)) + 2.0 * s * double(sizeof(uint32_t));  // nodes; order + leaves
}

// Every part holds a sample, so there are at most as many parts (and leaves) as samples; the parts are held twice
// while the chunks' lists are joined. Per sample: its part number, and per leaf a part count and first part.
double predict_leaf_summary_bytes(size_t samples) {
    return 2.0 * double(samples) * double(sizeof(LeafSummary)) + double(samples) * (2.0 * sizeof(uint32_t) + 1.0) +
           double(sizeof(uint32_t));
}

double predict_cone_bytes(size_t samples) { return 2.0 * double(samples) * double(sizeof(NormalCone) + 1); }

SplatMemory predict_splat_memory(SplatMethod method, size_t samples, size_t photons, const ClusterHierarchy* hierarchy,
                                 const Camera& camera, Kernel kernel, int threads) {
    SplatMemory m;
    const double s = double(samples), p = double(photons);
    const double nodes = hierarchy ? double(hierarchy->nodes.size()) : 0.0;
    const double positions = p * double(sizeof(glm::vec3));  // photon positions relative to the samples' origin
    const double sums = s * double(sizeof(glm::dvec3));      // per-sample sums kept between batches
    switch (method) {
        case SplatMethod::brute:
            m.fixed["photon_positions"] = positions;
            break;
        case SplatMethod::gather:
            // Grid photons (position, index, record), the sort entries they are made from, the hash table (at most
            // 2 cells per photon rounded up to a power of two: 4 × 16 bytes a photon), the positions.
            m.fixed["photon_grid"] = p * double(sizeof(glm::vec3) + 4 + sizeof(Photon)) + p * 4.0 * 16.0;
            m.fixed["photon_positions"] = positions + p * 16.0;
            // Each thread's candidate list and near list hold at most every photon once.
            m.fixed["gather_lists"] = double(std::max(threads, 1)) * std::min(p, 65536.0) * 16.0;
            break;
        case SplatMethod::tiled: {
            const double tiles = std::ceil(camera.width() / 32.0) * std::ceil(camera.height() / 32.0);
            m.fixed["tile_bounds"] = tiles * (12.0 + 2.0 * 24.0) + (camera.width() + camera.height()) * 16.0 / 32.0 + 64.0;
            m.fixed["tile_samples"] = (s + tiles + s / 32.0 + 2.0) * 4.0;
            m.fixed["photon_positions"] = positions;
            m.pair_key = "tile_photon_lists";
            m.pair_fixed = p * 8.0 + tiles * 8.0 + double(std::max(threads, 1)) * 64.0;  // counts, offsets, chunks
            m.fixed["splat_sample_sums"] = sums;
            m.per_pair = kBytesPerPair;
            break;
        }
        case SplatMethod::cluster:
        case SplatMethod::cluster_cone:
            m.fixed["photon_positions"] = positions;
            m.fixed["splat_sample_sums"] = sums;
            m.pair_key = "leaf_photon_lists";
            m.pair_fixed = (nodes + 2.0) * double(sizeof(size_t));  // per-node offsets of a batch
            m.per_pair = kBytesPerPair;
            if (method == SplatMethod::cluster_cone) {
                m.fixed["cone_traversal_nodes"] = nodes * 48.0;
                m.fixed["accepted_flux"] = nodes * (32.0 + (kernel == Kernel::uniform ? 0.0 : 5.0 * 24.0));
            }
            break;
        case SplatMethod::directional:
            // 8 direction bins × 6 slots of 8 bytes per node at most (the cut level has fewer), and the cut's
            // bookkeeping (facets, cuts, walk, parent/height/order) per node, the cut of every sample.
            m.fixed["direction_bins"] = nodes * 8.0 * 6.0 * 8.0;
            m.fixed["directional_nodes"] = nodes * 256.0 + s * 8.0;
            m.fixed["photon_positions"] = positions;
            // When the radius is below a leaf's size it falls back to the exact cluster splat and its pair lists.
            m.fixed["splat_sample_sums"] = sums;
            m.pair_key = "leaf_photon_lists";
            m.pair_fixed = (nodes + 2.0) * double(sizeof(size_t));
            m.per_pair = kBytesPerPair;
            break;
    }
    return m;
}

void reserve_frame(MemoryBudget& budget, const Scene& scene, const Camera& camera, const RenderSettings& settings) {
    const int w = camera.width(), h = camera.height();
    const size_t samples = size_t(w) * size_t(h);  // one a pixel; reserve_split_samples adds the rest
    budget.reserve("embree_scene", predict_embree_bytes(scene), "the scene's triangle count");
    budget.reserve("view_samples", predict_view_sample_bytes(w, h), "resolution");
    budget.reserve("view_sample_scratch", predict_view_sample_scratch_bytes(w, h), "resolution");
    budget.release("view_sample_scratch");
    budget.reserve("direct_light", predict_per_sample_light_bytes(samples), "resolution");
    // Aimed photons (caustic_aim.h) store at most one photon each.
    bool specular = false;
    for (const Material& m : scene.materials()) specular = specular || m.is_specular();
    const double aimed = specular ? std::ceil(double(settings.aimed_photons) * double(settings.photons)) : 0.0;
    const double photon_map = predict_photon_map_bytes(scene, settings.photons, settings.max_bounces) +
                              aimed * double(sizeof(Photon));
    budget.reserve("photon_map", photon_map, "photons");
    // While tracing, the photons sit in per-chunk vectors (up to twice their size) before the map is filled.
    budget.reserve("photon_trace_scratch", 2.0 * photon_map, "photons");
    budget.release("photon_trace_scratch");
    if (builds_hierarchy(settings.method))
        budget.reserve("hierarchy", predict_hierarchy_bytes(samples), "resolution");
    if (settings.method == SplatMethod::cluster_cone) budget.reserve("cones", predict_cone_bytes(samples), "resolution");
    if (settings.method == SplatMethod::directional)
        budget.reserve("leaf_summaries", predict_leaf_summary_bytes(samples), "resolution");
    budget.reserve("indirect_light", predict_per_sample_light_bytes(samples), "resolution");
    if (settings.boundary_correction)  // with the index of each pixel's first sample (samples = pixels here)
        budget.reserve("kernel_coverage", predict_kernel_coverage_bytes(samples) + double(samples) * sizeof(uint32_t),
                       "resolution");
    if (settings.caustics_pass) {
        // The caustic photons copied out of the map, and their own splat's light.
        budget.reserve("caustic_photons", photon_map, "photons");
        budget.reserve("caustic_light", predict_per_sample_light_bytes(samples), "resolution");
    }
    budget.reserve("image", predict_image_bytes(w, h, settings.caustics_pass), "resolution");
}

void reserve_split_samples(MemoryBudget& budget, const RenderSettings& settings, size_t pixels, size_t samples) {
    if (samples <= pixels) return;
    // Each per-sample structure grows by what its prediction for `samples` adds to the one for `pixels`, recorded
    // under its own name (so every structure's prediction still bounds what it measures).
    const auto grow = [&](const char* structure, double (*predict)(size_t)) {
        budget.reserve(structure, predict(samples) - predict(pixels), "resolution");
    };
    budget.reserve("view_samples", double(samples - pixels) * double(sizeof(ViewSample)), "resolution");
    grow("direct_light", predict_per_sample_light_bytes);
    if (builds_hierarchy(settings.method))
        grow("hierarchy", predict_hierarchy_bytes);
    if (settings.method == SplatMethod::cluster_cone) grow("cones", predict_cone_bytes);
    if (settings.method == SplatMethod::directional) grow("leaf_summaries", predict_leaf_summary_bytes);
    grow("indirect_light", predict_per_sample_light_bytes);
    if (settings.boundary_correction) grow("kernel_coverage", predict_kernel_coverage_bytes);
    if (settings.caustics_pass) grow("caustic_light", predict_per_sample_light_bytes);
}

void check_frame_memory(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        double extra_bytes_per_pixel) {
    Stats stats;
    MemoryBudget budget(settings.memory_budget, stats);
    budget.reserve("progressive_sums", double(camera.width()) * camera.height() * extra_bytes_per_pixel, "resolution");
    reserve_frame(budget, scene, camera, settings);
}

uint64_t fit_pair_cap(MemoryBudget& budget, SplatMethod method, const SplatMemory& memory) {
    const std::string lower = "photons or resolution";
    for (const auto& [name, bytes] : memory.fixed) budget.reserve(name, bytes, lower);
    if (memory.per_pair <= 0.0) return kDefaultMaxPairsInMemory;
    const double room = budget.remaining() - memory.pair_fixed;
    const double fits = budget.limit() > 0.0 ? std::floor(room / memory.per_pair) : double(kDefaultMaxPairsInMemory);
    const uint64_t cap = fits >= double(kDefaultMaxPairsInMemory) ? kDefaultMaxPairsInMemory
                                                                   : uint64_t(std::max(fits, double(kMinPairCap)));
    budget.reserve(memory.pair_key, memory.pair_fixed + double(cap) * memory.per_pair, "radius, photons or resolution");
    return cap;
}

}  // namespace ps
