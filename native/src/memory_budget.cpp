#include "photonsplat/memory_budget.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/photons.h"
#include "photonsplat/film.h"
#include "photonsplat/settings.h"
#include "photonsplat/splatter.h"
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

// The cap never goes below this many pairs: below it the splat would run in thousands of batches.
constexpr uint64_t kMinPairCap = uint64_t(1) << 20;

// The per-sample structures of the hierarchy a method splats onto (none for the methods that build none), by
// Stats::bytes name, for `samples` view samples.
std::vector<std::pair<const char*, double>> hierarchy_structures(const Splatter& splatter, size_t samples) {
    const std::optional<ClusterBuildOptions> options = splatter.hierarchy_options();
    if (!options) return {};
    std::vector<std::pair<const char*, double>> structures = {{"hierarchy", predict_hierarchy_bytes(samples)}};
    if (options->normal_cones) structures.emplace_back("cones", predict_cone_bytes(samples));
    if (options->leaf_summaries) structures.emplace_back("leaf_summaries", predict_leaf_summary_bytes(samples));
    return structures;
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

double predict_image_bytes(int width, int height, FilmOutputSet outputs) {
    // The film's outputs, and the emission, direct and indirect images that combined is summed from where the film
    // does not keep them.
    outputs |= film_bit(FilmOutput::combined);
    double floats = 0.0;
    for (const FilmOutputInfo& info : film_outputs())
        if (contains(outputs, info.output)) floats += info.channels;
    for (FilmOutput part : {FilmOutput::emission, FilmOutput::direct, FilmOutput::indirect})
        if (!contains(outputs, part)) floats += 3;
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
        if (m.has_delta) specular = true;
        if (!m.has_lobes) continue;
        if (m.directional || m.transmits || m.has_delta || m.textured) {
            a = 1.0;  // lobes, mixes and textures: bounded by 1 only
            continue;
        }
        glm::vec3 albedo(0.0f);
        for (const Closure& c : m.closures) albedo += c.color;
        a = std::max(a, double(std::max({albedo.x, albedo.y, albedo.z})));
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
    for (const Material& m : scene.materials()) specular = specular || m.has_delta;
    const double aimed = specular ? std::ceil(double(settings.aimed_photons) * double(settings.photons)) : 0.0;
    const double photon_map = predict_photon_map_bytes(scene, settings.photons, settings.max_bounces) +
                              aimed * double(sizeof(Photon));
    budget.reserve("photon_map", photon_map, "photons");
    // While tracing, the photons sit in per-chunk vectors (up to twice their size) before the map is filled.
    budget.reserve("photon_trace_scratch", 2.0 * photon_map, "photons");
    budget.release("photon_trace_scratch");
    for (const auto& [structure, bytes] : hierarchy_structures(*make_splatter(settings), samples))
        budget.reserve(structure, bytes, "resolution");
    budget.reserve("indirect_light", predict_per_sample_light_bytes(samples), "resolution");
    if (settings.boundary_correction)  // with the index of each pixel's first sample (samples = pixels here)
        budget.reserve("kernel_coverage", predict_kernel_coverage_bytes(samples) + double(samples) * sizeof(uint32_t),
                       "resolution");
    if (contains(requested_outputs(settings), FilmOutput::caustics)) {
        // The caustic photons copied out of the map (for one of its two splats at a time), and the two splats'
        // light while they are summed.
        budget.reserve("caustic_photons", photon_map, "photons");
        budget.reserve("caustic_light", 2.0 * predict_per_sample_light_bytes(samples), "resolution");
    }
    budget.reserve("image", predict_image_bytes(w, h, requested_outputs(settings)), "resolution");
}

void reserve_split_samples(MemoryBudget& budget, const RenderSettings& settings, size_t pixels, size_t samples,
                           size_t lobes, bool transmitted_direct, size_t terminator_lifts, size_t far_sides) {
    // The lobes of glossy samples, the light that came through rough transmission (transmitted_direct and its
    // caustic part, caustic_emission: a vec3 a pixel each), the samples' terminator lifts and the far sides of
    // translucent surfaces, known once traced.
    const double extra = double(lobes) * double(sizeof(Lobe)) + double(far_sides) * double(sizeof(ViewSample)) +
                         (transmitted_direct ? 2.0 * double(pixels) * sizeof(glm::vec3) : 0.0) +
                         double(terminator_lifts) * double(sizeof(ViewSamples::SampleLift));
    if (extra > 0.0) budget.reserve("view_samples", extra, "resolution");
    if (samples <= pixels) return;
    // Each per-sample structure grows by what its prediction for `samples` adds to the one for `pixels`, recorded
    // under its own name (so every structure's prediction still bounds what it measures).
    const auto grow = [&](const char* structure, double (*predict)(size_t)) {
        budget.reserve(structure, predict(samples) - predict(pixels), "resolution");
    };
    budget.reserve("view_samples", double(samples - pixels) * double(sizeof(ViewSample)), "resolution");
    grow("direct_light", predict_per_sample_light_bytes);
    const std::unique_ptr<Splatter> splatter = make_splatter(settings);
    const auto before = hierarchy_structures(*splatter, pixels), after = hierarchy_structures(*splatter, samples);
    for (size_t i = 0; i < after.size(); ++i)
        budget.reserve(after[i].first, after[i].second - before[i].second, "resolution");
    grow("indirect_light", predict_per_sample_light_bytes);
    if (settings.boundary_correction) grow("kernel_coverage", predict_kernel_coverage_bytes);
    if (contains(requested_outputs(settings), FilmOutput::caustics)) {
        grow("caustic_light", predict_per_sample_light_bytes);
        grow("caustic_light", predict_per_sample_light_bytes);
    }
}

void check_frame_memory(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        double extra_bytes_per_pixel) {
    Stats stats;
    MemoryBudget budget(settings.memory_budget, stats);
    budget.reserve("progressive_sums", double(camera.width()) * camera.height() * extra_bytes_per_pixel, "resolution");
    reserve_frame(budget, scene, camera, settings);
}

uint64_t fit_pair_cap(MemoryBudget& budget, const SplatMemory& memory) {
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
