// What the splatting tests share: the lists of methods, synthetic view samples and photons (random tilted planes
// seen by a pinhole camera looking down −z), splat parameters and counters, running any method by its enum, the
// comparison of a method with the brute-force oracle, and a cancel from another thread while a splat runs.
// Calls into the splatting API are kept here (run_splat, the method lists) so that a change of that API changes
// few lines of the tests.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "photonsplat/camera.h"
#include "photonsplat/direct_light.h"
#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/photons.h"
#include "photonsplat/progressive.h"
#include "photonsplat/reference.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/splatter.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"
#include "test_scenes.h"

namespace ps::test {

// ---- the methods ------------------------------------------------------------------------------------------

// Every splatting method the core offers, in its own order.
inline std::vector<SplatMethod> all_methods() {
    std::vector<SplatMethod> methods;
    for (const SplatMethodInfo& info : splat_methods()) methods.push_back(info.method);
    return methods;
}

inline std::vector<SplatMethod> exact_methods() {
    std::vector<SplatMethod> methods;
    for (const SplatMethodInfo& info : splat_methods())
        if (info.exact) methods.push_back(info.method);
    return methods;
}

// Names parameterised tests by their method: Suite.Test/cluster_cone.
inline std::string method_name(const ::testing::TestParamInfo<SplatMethod>& info) { return to_string(info.param); }

// ---- synthetic samples and photons ------------------------------------------------------------------------

constexpr float kTanHalfFov = 0.57735027f;  // the synthetic camera's 60° vertical field of view

inline ClusterKeyParams key_params(int width, int height) {
    ClusterKeyParams params;
    params.width = width;
    params.height = height;
    params.near_clip = 0.1f;
    params.vertical_half_extent = kTanHalfFov;
    return params;
}

inline glm::vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const glm::vec3 v(g(rng), g(rng), g(rng));
        const float len = glm::length(v);
        if (len > 1e-3f) return v / len;
    }
}

struct SyntheticOptions {
    int width = 48, height = 40;
    double coverage = 0.95;          // fraction of pixels with a sample
    double specular_fraction = 0.1;  // samples "seen through a mirror": moved to random places, random normals
    double glossy_fraction = 0.0;    // samples flagged kGlossy with a specular tint
    bool draws_glossy = false;       // draw the glossy choice for every sample (a random number each), even at 0
    int planes = 4;
    float min_depth = 1.0f, max_depth = 20.0f;
    bool axis_aligned = false;                // planes facing the camera exactly (flat cones, many accepts)
    glm::vec3 origin{250.0f, -40.0f, 12.0f};  // world position of the camera
    glm::vec3 offset{0.0f};                   // added to every sample's relative position
};

// The scenes of the cluster_cone tests: another origin, and the glossy choice drawn for every sample.
inline SyntheticOptions cone_scene_options() {
    SyntheticOptions o;
    o.origin = glm::vec3(-120.0f, 33.0f, 7.0f);
    o.draws_glossy = true;
    return o;
}

// A plane n·x = d.
struct Plane {
    glm::vec3 n;
    float d;
};

// Planes at depths in [min_depth, max_depth] along −z, tilted at random unless axis_aligned.
inline std::vector<Plane> random_planes(std::mt19937& rng, int count, float min_depth, float max_depth,
                                        bool axis_aligned = false) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<Plane> planes;
    for (int i = 0; i < count; ++i) {
        const glm::vec3 n = axis_aligned ? glm::vec3(0, 0, 1)
                                         : glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, 0.5f + u(rng)));
        planes.push_back({n, -(min_depth + (max_depth - min_depth) * u(rng)) * n.z});
    }
    return planes;
}

// The synthetic camera's ray direction through pixel (x, y) of a width × height image (z = −1).
inline glm::vec3 synthetic_pixel_direction(int x, int y, int width, int height) {
    const float aspect = float(width) / float(height);
    return glm::vec3((2.0f * (x + 0.5f) / width - 1.0f) * kTanHalfFov * aspect,
                     (1.0f - 2.0f * (y + 0.5f) / height) * kTanHalfFov, -1.0f);
}

// The nearest plane along dir: its ray parameter (infinite when none is hit) and its normal facing the ray.
inline std::pair<float, glm::vec3> nearest_plane(const std::vector<Plane>& planes, const glm::vec3& dir) {
    float t_best = INFINITY;
    glm::vec3 n_best(0, 0, 1);
    for (const Plane& plane : planes) {
        const float t = plane.d / glm::dot(plane.n, dir);
        if (t > 0.0f && t < t_best) t_best = t, n_best = plane.n;
    }
    return {t_best, glm::dot(n_best, dir) < 0.0f ? n_best : -n_best};
}

// Gives s directional lobes, stored in vs.lobes: a GGX reflection (Schlick tint) always, and by `pick` one more
// closure of each other reflection kind in turn (Beckmann, anisotropic GGX, multiscatter GGX, clearcoat, sheen,
// velvet, Oren–Nayar, principled diffuse), so that the exactness suites meet every closure a view sample holds.
inline void add_glossy_lobe(ViewSamples& vs, ViewSample& s, const glm::vec3& f0, float alpha) {
    Lobe l;
    l.kind = ClosureKind::reflection;
    l.distribution = Distribution::ggx;
    l.fresnel = FresnelKind::schlick;
    l.weight = glm::vec3(1.0f);
    l.specular_color = f0;
    l.alpha_x = l.alpha_y = alpha;
    if (!(s.flags & kGlossy)) {
        s.lobe_begin = static_cast<uint32_t>(vs.lobes.size());
        s.lobe_count = 0;
    }
    vs.lobes.push_back(l);
    ++s.lobe_count;
    s.flags |= kGlossy;
}

inline void add_random_lobes(ViewSamples& vs, ViewSample& s, float u1, float u2, float pick) {
    add_glossy_lobe(vs, s, glm::vec3(0.04f + 0.5f * u1), 0.05f + 0.5f * u2);
    Lobe l;
    l.weight = glm::vec3(0.3f + 0.5f * u2, 0.4f, 0.2f + 0.5f * u1);
    l.alpha_x = l.alpha_y = 0.1f + 0.6f * u1;
    l.roughness = u2;
    l.eta = 1.5f;
    switch (static_cast<int>(pick * 9.0f)) {
        case 0: l.kind = ClosureKind::reflection; l.distribution = Distribution::beckmann; break;
        case 1:
            l.kind = ClosureKind::reflection;
            l.alpha_y = 0.5f * l.alpha_x;
            l.tangent = glm::normalize(glm::cross(s.shading_normal, glm::vec3(0.3f, 0.5f, 0.8f)));
            break;
        case 2: l.kind = ClosureKind::reflection; l.distribution = Distribution::multi_ggx; break;
        case 3:
            l.kind = ClosureKind::reflection;
            l.distribution = Distribution::gtr1;
            l.fresnel = FresnelKind::dielectric;
            break;
        case 4: l.kind = ClosureKind::sheen; break;
        case 5: l.kind = ClosureKind::velvet; break;
        case 6: l.kind = ClosureKind::diffuse; break;
        case 7: l.kind = ClosureKind::principled_diffuse; break;
        default:
            l.kind = ClosureKind::reflection;
            l.fresnel = FresnelKind::principled;
            l.specular_color = glm::vec3(0.9f, 0.6f, 0.3f);
            break;
    }
    vs.lobes.push_back(l);
    ++s.lobe_count;
}

// A pinhole camera at `origin` looking down −z at a few planes: a sample per covered pixel on the nearest plane,
// with random albedo.
inline ViewSamples synthetic_view_samples(const SyntheticOptions& o, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ViewSamples vs;
    vs.width = o.width;
    vs.height = o.height;
    vs.origin = o.origin;
    const std::vector<Plane> planes = random_planes(rng, o.planes, o.min_depth, o.max_depth, o.axis_aligned);
    for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
            if (u(rng) > o.coverage) continue;
            const glm::vec3 dir = synthetic_pixel_direction(x, y, o.width, o.height);
            const auto [t_best, normal] = nearest_plane(planes, dir);
            if (!std::isfinite(t_best)) continue;
            ViewSample s{};
            s.position = dir * t_best + o.offset;
            s.normal = s.shading_normal = normal;
            s.wo = -glm::normalize(dir);
            s.albedo = glm::vec3(u(rng), u(rng), u(rng));
            s.throughput = glm::vec3(1.0f);
            s.pixel = uint32_t(y * o.width + x);
            s.depth = t_best;
            if (u(rng) < o.specular_fraction) {
                s.flags = kViaSpecular;
                s.position = glm::vec3(u(rng) * 8.0f - 4.0f, u(rng) * 8.0f - 4.0f, -2.0f - u(rng) * 10.0f) + o.offset;
                s.normal = s.shading_normal = random_unit(rng);
                s.throughput = glm::vec3(0.2f + u(rng), 0.2f + u(rng), 0.2f + u(rng));
            }
            if ((o.draws_glossy || o.glossy_fraction > 0.0) && u(rng) < o.glossy_fraction)
            {
                const float u1 = u(rng), u2 = u(rng), pick = u(rng);
                add_random_lobes(vs, s, u1, u2, pick);
            }
            vs.samples.push_back(s);
        }
    return vs;
}

// The camera the synthetic samples are seen by (what tiled splats with, and the hierarchy's keys).
inline Camera synthetic_camera(const SyntheticOptions& o) {
    glm::dmat4 to_world(1.0);
    to_world[3] = glm::dvec4(glm::dvec3(o.origin), 1.0);
    return Camera(to_world, perspective(60.0f, float(o.width) / float(o.height), 0.1f, 1000.0f), o.width, o.height);
}

struct PhotonOptions {
    float normal_jitter = 0.3f;   // most photon normals: the sample's, tilted by this × a random unit vector
    float wi_near_normal = 0.0f;  // > 0: that fraction of ωi near the photon's normal (the rest at random)
    bool caustic_flags = true;    // a tenth flagged kCaustic
    uint64_t emitted_per_photon = 3, emitted_extra = 1;  // N_emitted = count × per photon + extra
};

// The photons of the cluster_cone tests: ωi mostly near the photon's normal, so that whole nodes face them.
inline PhotonOptions cone_photon_options() {
    PhotonOptions o;
    o.normal_jitter = 0.2f;
    o.wi_near_normal = 0.7f;
    o.caustic_flags = false;
    o.emitted_per_photon = 2;
    o.emitted_extra = 3;
    return o;
}

// Photons around random samples (within `spread`), mostly on the sample's side and orientation, sometimes not,
// so that every branch of the per-sample test is exercised.
inline PhotonMap synthetic_photons(const ViewSamples& vs, size_t count, float spread, std::mt19937& rng,
                                   const PhotonOptions& o = {}) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    PhotonMap map;
    map.emitted = count * o.emitted_per_photon + o.emitted_extra;
    for (size_t i = 0; i < count && !vs.samples.empty(); ++i) {
        const ViewSample& s = vs.samples[size_t(u(rng) * float(vs.samples.size())) % vs.samples.size()];
        Photon p{};
        p.position = vs.origin + s.position + random_unit(rng) * (spread * u(rng));
        p.normal = u(rng) < 0.8f ? glm::normalize(s.normal + o.normal_jitter * random_unit(rng)) : random_unit(rng);
        if (o.wi_near_normal > 0.0f)
            p.wi = u(rng) < o.wi_near_normal ? glm::normalize(p.normal + 0.8f * random_unit(rng)) : random_unit(rng);
        else
            p.wi = random_unit(rng);
        if (glm::dot(p.wi, p.normal) < 0.0f) p.wi = -p.wi;
        p.power = glm::vec3(0.5f + u(rng), 0.5f + u(rng), 0.5f + u(rng));
        if (o.caustic_flags) p.flags = u(rng) < 0.1f ? kCaustic : 0u;
        map.photons.push_back(p);
    }
    return map;
}

// A sample of pixel `pixel` at `position`, `depth` from the camera, on a surface facing the camera (+z), albedo
// (0.8, 0.5, 0.25).
inline ViewSample facing_sample(const glm::vec3& position, float depth, uint32_t pixel) {
    ViewSample s{};
    s.depth = depth;
    s.position = position;
    s.normal = s.shading_normal = s.wo = glm::vec3(0, 0, 1);
    s.albedo = glm::vec3(0.8f, 0.5f, 0.25f);
    s.throughput = glm::vec3(1.0f);
    s.pixel = pixel;
    return s;
}

// A grid of 32 × 32 samples facing the camera at binary-fraction positions (distances between them and photons
// placed at binary fractions are exact in float), at depth 2 or 8 by columns of 4: depth discontinuities inside
// tiles. Origin 0, so that world and relative positions are the same.
inline ViewSamples binary_grid_samples() {
    ViewSamples vs;
    vs.width = 32;
    vs.height = 32;
    vs.origin = glm::vec3(0.0f);
    for (uint32_t pixel = 0; pixel < 32 * 32; ++pixel) {
        const uint32_t x = pixel % 32, y = pixel / 32;
        const float depth = (x / 4) % 2 ? 2.0f : 8.0f;
        vs.samples.push_back(facing_sample(glm::vec3(float(x) * 0.25f, float(y) * 0.25f, -depth), depth, pixel));
    }
    return vs;
}

// A photon at `position` on a surface facing +z, arriving along wi (towards the light).
inline Photon photon_at(const glm::vec3& position, const glm::vec3& wi, const glm::vec3& power = glm::vec3(1.0f)) {
    Photon p{};
    p.position = position;
    p.wi = wi;
    p.normal = glm::vec3(0, 0, 1);
    p.power = power;
    return p;
}

// ---- parameters and counters --------------------------------------------------------------------------------

inline SplatParams splat_params(float radius, const PhotonMap& map, Kernel kernel = Kernel::uniform) {
    SplatParams params;
    params.radius = radius;
    params.emitted = map.emitted;  // 0 with no photons stored: valid
    params.kernel = kernel;
    return params;
}

// A counter's value, −1 when the method did not report it (so that a missing counter never passes for 0).
inline double counter(const Stats& stats, const char* name) {
    const auto it = stats.counters.find(name);
    return it == stats.counters.end() ? -1.0 : it->second;
}

// ---- running a method ---------------------------------------------------------------------------------------

// The registered splatter of a method, with the directional level of `params` as its setting.
inline std::unique_ptr<Splatter> splatter_for(SplatMethod method, const SplatParams& params = {}) {
    RenderSettings settings;
    settings.method = method;
    settings.directional_level = params.directional_level;
    return make_splatter(settings);
}

// The hierarchy a method splats over, built as the method asks (normal cones for cluster_cone, leaf summaries
// for directional); none for brute, tiled and gather.
inline ClusterHierarchy hierarchy_for(SplatMethod method, const ViewSamples& vs, const ClusterKeyParams& key) {
    const std::optional<ClusterBuildOptions> options = splatter_for(method)->hierarchy_options();
    return options ? build_cluster_hierarchy(vs, key, *options) : ClusterHierarchy{};
}

// What one splat reads: the samples, the hierarchy over them (cluster, cluster_cone, directional), the camera
// that saw them (tiled).
struct SplatInput {
    const ViewSamples& samples;
    const ClusterHierarchy* hierarchy = nullptr;
    const Camera* camera = nullptr;
};

inline std::vector<glm::vec3> run_splat(SplatMethod method, const SplatInput& in, const PhotonMap& map,
                                        const SplatParams& params, const RenderControl& control, Stats& stats) {
    const std::unique_ptr<Splatter> splatter = splatter_for(method, params);
    const bool needs_hierarchy = splatter->hierarchy_options().has_value();
    if ((needs_hierarchy && !in.hierarchy) || (method == SplatMethod::tiled && !in.camera)) {
        ADD_FAILURE() << to_string(method) << " needs " << (needs_hierarchy ? "a hierarchy" : "a camera");
        return {};
    }
    static const Camera unused(glm::dmat4(1.0), glm::mat4(1.0f), 1, 1);  // only tiled reads the camera
    const SplatFrame frame{in.samples, in.camera ? *in.camera : unused, in.hierarchy, 0, 0};
    return splatter->splat(frame, map, params, control, stats).radiance;
}

// A method's samples and the camera that saw them, with the hierarchy the method needs.
struct MethodFrame {
    ViewSamples samples;
    Camera camera;
    ClusterHierarchy hierarchy;
    MethodFrame(SplatMethod method, ViewSamples vs, const Camera& cam)
        : samples(std::move(vs)), camera(cam),
          hierarchy(hierarchy_for(method, samples, ClusterKeyParams::from_camera(cam))) {}
    SplatInput input() const { return {samples, &hierarchy, &camera}; }
};

// Synthetic samples drawn from rng, seen by the synthetic camera, with the hierarchy `method` needs.
inline MethodFrame synthetic_frame(SplatMethod method, const SyntheticOptions& o, std::mt19937& rng) {
    return MethodFrame(method, synthetic_view_samples(o, rng), synthetic_camera(o));
}

// A method's synthetic frame and `count` photons around its samples (within `spread`), drawn in that order from
// one generator seeded with `seed`.
struct SyntheticSplat {
    MethodFrame frame;
    PhotonMap map;
};

inline SyntheticSplat synthetic_splat(SplatMethod method, uint32_t seed, size_t count, float spread,
                                      const SyntheticOptions& o = {}) {
    std::mt19937 rng(seed);
    MethodFrame frame = synthetic_frame(method, o, rng);
    PhotonMap map = synthetic_photons(frame.samples, count, spread, rng);
    return {std::move(frame), std::move(map)};
}

// The default synthetic options at another image size.
inline SyntheticOptions sized(int width, int height, SyntheticOptions o = {}) {
    o.width = width;
    o.height = height;
    return o;
}

// ---- comparing with the oracle --------------------------------------------------------------------------------

// Each sample and channel of `actual` finite and within 1e-4 relative of `expected`; the first few failures are
// reported one by one. Returns how many samples are bit-identical.
inline size_t expect_close(const std::vector<glm::vec3>& actual, const std::vector<glm::vec3>& expected,
                           const std::string& what, size_t max_reports = 5) {
    EXPECT_EQ(actual.size(), expected.size()) << what;
    const size_t n = std::min(actual.size(), expected.size());
    size_t failures = 0, identical = 0;
    for (size_t i = 0; i < n; ++i) {
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) {
            const float a = actual[i][ch], e = expected[i][ch];
            const bool ok = std::isfinite(a) && std::fabs(a - e) <= 1e-4f * std::max(std::fabs(a), std::fabs(e));
            if (!ok && ++failures <= max_reports)
                ADD_FAILURE() << what << ": sample " << i << " channel " << ch << ": " << a << ", brute " << e;
            same = same && a == e;
        }
        identical += same ? 1 : 0;
    }
    EXPECT_EQ(failures, 0u) << what;
    return identical;
}

struct Comparison {
    size_t samples = 0, identical = 0;
    Stats brute, method;
    std::vector<glm::vec3> expected, actual;
};

// `method` against brute on the same input: 1e-4 relative per sample and channel, the same contributing pairs
// (culling only removes tests), never more per-sample tests.
inline Comparison compare_with_brute(SplatMethod method, const SplatInput& in, const PhotonMap& map,
                                     const SplatParams& params, const std::string& what = "") {
    Comparison c;
    RenderControl control;
    c.expected = splat_brute(in.samples, map, params, control, c.brute);
    c.actual = run_splat(method, in, map, params, control, c.method);
    EXPECT_EQ(c.expected.size(), in.samples.samples.size()) << what;
    EXPECT_EQ(c.actual.size(), in.samples.samples.size()) << what;
    c.samples = std::min(c.expected.size(), c.actual.size());
    c.identical = expect_close(c.actual, c.expected, std::string(to_string(method)) + " " + what);
    EXPECT_EQ(counter(c.method, "contributing_pairs"), counter(c.brute, "contributing_pairs")) << what;
    EXPECT_LE(counter(c.method, "photon_sample_tests"), counter(c.brute, "photon_sample_tests")) << what;
    return c;
}

// ---- renders of the Cornell box ------------------------------------------------------------------------------

// The Cornell box with its glass and mirror spheres, built once.
inline const Scene& cornell_scene() {
    static const Scene* scene = [] {
        auto* s = new Scene;
        build_cornell_box(*s, true);
        return s;
    }();
    return *scene;
}

// Two renders' indirect components agree to 1e-4 relative (of the first, floored at 1e-6), and the first is
// not all black (`why_not_black` says why that matters).
inline void expect_same_indirect(const RenderResult& expected, const RenderResult& actual,
                                 const char* why_not_black = "") {
    const std::vector<float>& e = expected.film[ps::FilmOutput::indirect];
    const std::vector<float>& a = actual.film[ps::FilmOutput::indirect];
    ASSERT_EQ(e.size(), a.size());
    double sum = 0.0;
    for (size_t i = 0; i < e.size(); ++i) {
        EXPECT_LE(std::fabs(e[i] - a[i]), 1e-4f * std::max(std::fabs(e[i]), 1e-6f)) << "component " << i;
        sum += e[i];
    }
    EXPECT_GT(sum, 0.0) << why_not_black;
}

// Settings of a render with `method`, `photons` photon paths and `seed`; the rest left at their defaults.
inline RenderSettings method_settings(SplatMethod method, uint64_t photons, uint64_t seed) {
    RenderSettings settings;
    settings.method = method;
    settings.photons = photons;
    settings.seed = seed;
    return settings;
}

// The Cornell box of cornell_scene rendered with `settings`, seen by cornell_camera(width, height).
inline RenderResult render_cornell_box(const RenderSettings& settings, int width, int height) {
    RenderControl control;
    return render(cornell_scene(), cornell_camera(width, height), settings, control);
}

// Settings for a closed box of emissive walls: `photons` photon paths of up to `max_bounces`, kernel radius
// `radius`, `direct_samples` shadow rays a light.
inline RenderSettings emissive_box_settings(uint64_t photons, float radius, int max_bounces, int direct_samples) {
    RenderSettings settings;
    settings.photons = photons;
    settings.radius = radius;
    settings.max_bounces = max_bounces;
    settings.direct_samples = direct_samples;
    return settings;
}

// ---- direct light ------------------------------------------------------------------------------------------

// The view samples `camera` sees of `scene`, and the direct light at each of them.
struct DirectView {
    ViewSamples samples;
    std::vector<glm::vec3> direct;
};

inline DirectView direct_light_view(const Scene& scene, const Camera& camera,
                                    const DirectLightSettings& settings = DirectLightSettings{}) {
    RenderControl control;
    Stats stats;
    DirectView view;
    view.samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    view.direct = compute_direct_light(scene, view.samples, settings, control, stats);
    return view;
}

// ---- cancelling from another thread --------------------------------------------------------------------------

// Runs `body`, which must throw Cancelled, while another thread requests `control`'s cancel `delay` after the
// start; returns the seconds from the start to the throw.
inline double seconds_until_cancelled(RenderControl& control, std::chrono::milliseconds delay,
                                      const std::function<void()>& body) {
    std::atomic<bool> started{false};
    std::thread canceller([&] {
        while (!started) std::this_thread::yield();
        std::this_thread::sleep_for(delay);
        control.request_cancel();
    });
    const auto start = std::chrono::steady_clock::now();
    started = true;
    EXPECT_THROW(body(), Cancelled);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    canceller.join();
    return seconds;
}

// ---- images of whole renders ------------------------------------------------------------------------------

// The RGBA image of `iterations` progressive iterations with `settings` (and its stats, where asked for).
inline std::vector<float> progressive_image(const Scene& scene, const Camera& camera, RenderSettings settings,
                                            int iterations, Stats* stats = nullptr) {
    settings.iterations = iterations;
    RenderControl control;
    ProgressiveRender progressive(scene, camera, settings);
    for (int i = 0; i < iterations; ++i) progressive.run_iteration(control);
    if (stats) *stats = progressive.stats();
    return progressive.result().rgba();
}

// The reference renderer's RGBA image at `samples` per pixel, on two threads.
inline std::vector<float> reference_image(const Scene& scene, const Camera& camera, int samples) {
    ReferenceSettings settings;
    settings.samples = samples;
    settings.threads = 2;
    RenderControl control;
    return render_reference(scene, camera, settings, control).rgba;
}

// Mean of the RGB of pixels [x0, x1) × [y0, y1) of an RGBA image `width` pixels wide.
inline double block_mean(const std::vector<float>& rgba, int width, int x0, int x1, int y0, int y1) {
    double sum = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c) sum += rgba[(size_t(y) * width + x) * 4 + c];
    return sum / (3.0 * (x1 - x0) * (y1 - y0));
}

}  // namespace ps::test
