// The tiled splat (Mara et al. 2013) must give what the brute-force oracle gives, sample for sample: on scenes
// made by the real pipeline (view samples and photons traced through mirrors and glass), with radii from tiny to
// larger than the scene, cameras whose near plane photon spheres cross, orthographic cameras, images of 1×1 and
// of partial tiles, and with the pair cap so small that photons are splatted in many batches; also through the
// whole render. Then the sphere's screen bounds against brute-force sampling of pixel rays, counters, thread
// counts and cancellation. A benchmark against the cluster method at 1080p is disabled by default.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/photons.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"
#include "test_support.h"

namespace {

using namespace ps;
using namespace ps::test;

constexpr float kPi = 3.14159265358979f;

// An OpenGL orthographic projection of a view `2·half_height` tall.
glm::mat4 orthographic(float half_height, float aspect, float near, float far) {
    glm::mat4 p(1.0f);
    p[0][0] = 1.0f / (half_height * aspect);
    p[1][1] = 1.0f / half_height;
    p[2][2] = -2.0f / (far - near);
    p[3][2] = -(far + near) / (far - near);
    return p;
}

// A perspective camera with lens shift (an off-centre frustum), as Blender's shift_x/shift_y give.
Camera shifted_camera(glm::vec3 eye, glm::vec3 target, int width, int height, float fov_y, float shift_x,
                      float shift_y) {
    glm::mat4 p = test::perspective(fov_y, float(width) / float(height), 0.05f, 100.0f);
    p[2][0] = shift_x;
    p[2][1] = shift_y;
    return Camera(look_at_matrix(eye, target), p, width, height);
}

Camera orthographic_camera(glm::vec3 eye, glm::vec3 target, int width, int height, float half_height) {
    return Camera(look_at_matrix(eye, target), orthographic(half_height, float(width) / float(height), 0.1f, 50.0f),
                  width, height);
}

struct Frame {
    ViewSamples samples;
    PhotonMap photons;
};

// View samples and photons through the real pipeline.
Frame trace_frame(const Scene& scene, const Camera& camera, uint64_t photon_count, uint64_t seed) {
    RenderControl control;
    Stats stats;
    Frame f;
    ViewSampleSettings view_settings;
    view_settings.seed = seed;
    f.samples = generate_view_samples(scene, camera, view_settings, control, stats);
    PhotonSettings photon_settings;
    photon_settings.count = photon_count;
    photon_settings.seed = seed;
    f.photons = trace_photons(scene, photon_settings, control, stats);
    return f;
}

// A floor, randomly placed and tilted quads (diffuse, glossy, a mirror), a glass and a mirror sphere, a point
// light and sometimes a sun.
void build_random_scene(Scene& scene, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<uint32_t> diffuse;
    for (int i = 0; i < 3; ++i) {
        const glm::vec3 albedo(0.2f + 0.7f * u(rng), 0.2f + 0.7f * u(rng), 0.2f + 0.7f * u(rng));
        diffuse.push_back(
            scene.add_material({"diffuse" + std::to_string(i), MaterialKind::diffuse, albedo, 1.45f, glm::vec3(0.0f)}));
    }
    Material glossy{"glossy", MaterialKind::glossy, glm::vec3(0.9f, 0.8f, 0.6f), 1.45f, glm::vec3(0.0f)};
    glossy.roughness = 0.4f;
    const uint32_t glossy_id = scene.add_material(glossy);
    const uint32_t mirror =
        scene.add_material({"mirror", MaterialKind::mirror, glm::vec3(0.9f), 1.45f, glm::vec3(0.0f)});
    const uint32_t glass = scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
    // A room around everything (the camera stands inside), so that photons keep bouncing.
    const float e = 7.0f, top = 5.0f;
    test::add_quad(scene, "floor", {-e, -e, 0}, {e, -e, 0}, {e, e, 0}, {-e, e, 0}, diffuse[0]);
    test::add_quad(scene, "ceiling", {-e, -e, top}, {-e, e, top}, {e, e, top}, {e, -e, top}, diffuse[1]);
    test::add_quad(scene, "wall_n", {-e, e, 0}, {e, e, 0}, {e, e, top}, {-e, e, top}, diffuse[2]);
    test::add_quad(scene, "wall_s", {-e, -e, 0}, {-e, -e, top}, {e, -e, top}, {e, -e, 0}, diffuse[1]);
    test::add_quad(scene, "wall_e", {e, -e, 0}, {e, -e, top}, {e, e, top}, {e, e, 0}, diffuse[0]);
    test::add_quad(scene, "wall_w", {-e, -e, 0}, {-e, e, 0}, {-e, e, top}, {-e, -e, top}, diffuse[2]);
    for (int i = 0; i < 7; ++i) {
        const glm::vec3 c(4.0f * u(rng) - 2.0f, 4.0f * u(rng) - 2.0f, 0.2f + 2.0f * u(rng));
        const glm::vec3 n = random_unit(rng);
        const glm::vec3 a = glm::normalize(glm::cross(n, random_unit(rng)));
        const glm::vec3 b = glm::cross(n, a);
        const float sa = 0.3f + 0.8f * u(rng), sb = 0.3f + 0.8f * u(rng);
        const uint32_t m = i == 0 ? mirror : i == 1 ? glossy_id : diffuse[i % 3];
        test::add_quad(scene, "quad", c - sa * a - sb * b, c + sa * a - sb * b, c + sa * a + sb * b,
                       c - sa * a + sb * b, m);
    }
    test::add_sphere(scene, "glass", {4.0f * u(rng) - 2.0f, 4.0f * u(rng) - 2.0f, 0.6f}, 0.5f, glass, 12, 24);
    test::add_sphere(scene, "mirror_ball", {4.0f * u(rng) - 2.0f, 4.0f * u(rng) - 2.0f, 0.4f}, 0.4f, mirror, 12, 24);
    Light light;
    light.name = "lamp";
    light.position = {2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f, 3.5f};
    light.value = glm::vec3(200.0f / (4.0f * kPi));
    scene.add_light(light);
    if (u(rng) < 0.5f) {
        Light sun;
        sun.name = "sun";
        sun.kind = LightKind::sun;
        sun.direction = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, -1.0f));
        sun.value = glm::vec3(2.0f);
        scene.add_light(sun);
    }
}

// Totals over the whole file, printed by the last test.
size_t g_samples = 0, g_identical = 0;

// Tiled against brute (test::compare_with_brute), counted in the totals.
Comparison compare_with_brute(const ViewSamples& vs, const Camera& camera, const PhotonMap& map,
                              const SplatParams& params) {
    Comparison c = test::compare_with_brute(SplatMethod::tiled, {vs, nullptr, &camera}, map, params);
    g_samples += c.samples;
    g_identical += c.identical;
    return c;
}

void report(const std::string& what, const Comparison& c) {
    std::printf("%-36s %6zu samples, %6zu bit-identical, contributing %9.0f, sample tests brute %10.0f / tiled "
                "%10.0f, tile tests %8.0f, pairs %8.0f, batches %.0f, outside-frustum samples %.0f\n",
                what.c_str(), c.samples, c.identical, counter(c.brute, "contributing_pairs"),
                counter(c.brute, "photon_sample_tests"), counter(c.method, "photon_sample_tests"),
                counter(c.method, "photon_tile_tests"), counter(c.method, "tile_photon_pairs"),
                counter(c.method, "splat_batches"), counter(c.method, "samples_outside_tile_frustum"));
}

// Whether any sample seen through a mirror or glass received photons in the oracle.
bool via_specular_samples_lit(const ViewSamples& vs, const std::vector<glm::vec3>& radiance) {
    for (size_t i = 0; i < vs.samples.size(); ++i)
        if ((vs.samples[i].flags & kViaSpecular) && radiance[i] != glm::vec3(0.0f)) return true;
    return false;
}

// ---- exactness through the real pipeline ------------------------------------------------------------------

TEST(Tiled, MatchesBruteOnRandomPipelineScenes) {
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        std::mt19937 rng(seed);
        Scene scene;
        build_random_scene(scene, rng);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const float angle = 2.0f * kPi * u(rng);
        const glm::vec3 eye(5.5f * std::cos(angle), 5.5f * std::sin(angle), 1.0f + 2.0f * u(rng));
        const Camera camera = test::look_at(eye, {0.0f, 0.0f, 0.8f}, 128, 72, 45.0f);
        const Frame f = trace_frame(scene, camera, 600, seed);
        ASSERT_GT(f.photons.photons.size(), 600u);
        for (float radius : {1e-3f, 0.4f, seed == 1 ? 1e3f : 2.0f}) {  // the room is 14 × 14 × 5
            const std::string what = "random scene " + std::to_string(seed) + ", r " + std::to_string(radius);
            SCOPED_TRACE(what);
            const Comparison c = compare_with_brute(f.samples, camera, f.photons, splat_params(radius, f.photons));
            if (radius == 0.4f) {  // 4×3 tiles
                EXPECT_GT(counter(c.brute, "contributing_pairs"), 500.0);
                EXPECT_LT(counter(c.method, "photon_sample_tests"), 0.5 * counter(c.brute, "photon_sample_tests"));
            }
            if (seed == 1) report(what, c);
        }
    }
}

TEST(Tiled, MatchesBruteOnTheCornellBoxBehindGlassAndMirror) {
    const Camera camera = test::cornell_camera(48, 48);
    const Frame f = trace_frame(cornell_scene(), camera, 4000, 3);
    size_t via_specular = 0;
    for (const ViewSample& s : f.samples.samples) via_specular += (s.flags & kViaSpecular) ? 1 : 0;
    ASSERT_GT(via_specular, 50u) << "the glass and mirror spheres are in view";
    for (float radius : {1e-3f, 0.05f, 0.2f, 4.0f}) {  // the box's diagonal is 3.5
        const std::string what = "Cornell box, r " + std::to_string(radius);
        SCOPED_TRACE(what);
        const Comparison c = compare_with_brute(f.samples, camera, f.photons, splat_params(radius, f.photons));
        EXPECT_GT(counter(c.method, "samples_outside_tile_frustum"), 0.0);
        if (radius == 0.05f || radius == 0.2f) {
            EXPECT_TRUE(via_specular_samples_lit(f.samples, c.expected)) << "the comparison behind glass is vacuous";
        }
        report(what, c);
    }
}

// Partial tiles on both axes, and a single pixel.
TEST(Tiled, MatchesBruteOnOddImageSizes) {
    for (const auto& [w, h] : {std::pair<int, int>{33, 31}, {1, 1}, {65, 2}, {1, 40}}) {
        const Camera camera = test::cornell_camera(w, h);
        const Frame f = trace_frame(cornell_scene(), camera, 4000, 5);
        for (float radius : {0.1f, 5.0f}) {
            const std::string what = std::to_string(w) + "x" + std::to_string(h) + ", r " + std::to_string(radius);
            SCOPED_TRACE(what);
            const Comparison c = compare_with_brute(f.samples, camera, f.photons, splat_params(radius, f.photons));
            if (w == 33) report(what, c);
        }
    }
}

// The camera stands inside the box, just above the floor: photons on the floor right under it have spheres
// that cross the near plane and the eye plane (full-screen bounds).
TEST(Tiled, MatchesBruteWhenPhotonSpheresCrossTheNearPlane) {
    const glm::vec3 eye(0.0f, -0.6f, 0.12f);
    const Camera camera = test::look_at(eye, {0.1f, 1.0f, 0.3f}, 40, 32, 70.0f);
    const Frame f = trace_frame(cornell_scene(), camera, 6000, 9);
    const float radius = 0.25f;
    size_t crossing = 0;
    for (const Photon& p : f.photons.photons) crossing += camera.view_depth(p.position) < radius ? 1 : 0;
    ASSERT_GT(crossing, 20u) << "photon spheres reach the eye plane";
    const Comparison c = compare_with_brute(f.samples, camera, f.photons, splat_params(radius, f.photons));
    EXPECT_GT(counter(c.brute, "contributing_pairs"), 0.0);
    report("spheres crossing the near plane", c);
}

TEST(Tiled, MatchesBruteWithAnOrthographicCamera) {
    const Camera camera = orthographic_camera({0.3f, -5.0f, 1.1f}, {0.0f, 0.0f, 0.9f}, 100, 70, 1.2f);
    ASSERT_TRUE(camera.orthographic());
    const Frame f = trace_frame(cornell_scene(), camera, 1500, 11);
    for (float radius : {0.01f, 0.12f, 3.0f}) {
        const std::string what = "orthographic, r " + std::to_string(radius);
        SCOPED_TRACE(what);
        const Comparison c = compare_with_brute(f.samples, camera, f.photons, splat_params(radius, f.photons));
        if (radius == 0.12f) {
            EXPECT_LT(counter(c.method, "photon_sample_tests"), 0.5 * counter(c.brute, "photon_sample_tests"));
        }
        report(what, c);
    }
}

TEST(Tiled, MatchesBruteWithAShiftedWideCameraAndGlossyReceiversAndTheEpanechnikovKernel) {
    std::mt19937 rng(21);
    Scene scene;
    build_random_scene(scene, rng);
    const Camera camera = shifted_camera({0.5f, -4.5f, 2.0f}, {0.0f, 0.0f, 0.5f}, 50, 38, 95.0f, 0.35f, -0.2f);
    const Frame f = trace_frame(scene, camera, 4000, 21);
    SplatParams params = splat_params(0.2f, f.photons);
    params.kernel = Kernel::epanechnikov;
    params.plane_distance_factor = 0.25f;
    params.cos_normal_tolerance = 0.8f;
    const Comparison c = compare_with_brute(f.samples, camera, f.photons, params);
    EXPECT_GT(counter(c.brute, "contributing_pairs"), 0.0);
    report("shifted 95° camera, Epanechnikov", c);
}

// ---- bounded memory ---------------------------------------------------------------------------------------

TEST(Tiled, TinyPairCapGivesManyBatchesAndTheSameResultBitForBit) {
    const Camera camera = test::cornell_camera(40, 40);
    const Frame f = trace_frame(cornell_scene(), camera, 1200, 13);
    for (float radius : {0.3f, 1e3f}) {
        SplatParams params = splat_params(radius, f.photons);
        const Comparison reference = compare_with_brute(f.samples, camera, f.photons, params);
        ASSERT_EQ(counter(reference.method, "splat_batches"), 1.0);
        const double pairs = counter(reference.method, "tile_photon_pairs");
        // Caps of a few pairs, and the total itself (kept by the counting pass: one batch) and one less (binned
        // again in two batches).
        for (uint64_t cap : {uint64_t(1), uint64_t(7), uint64_t(200), uint64_t(pairs) - 1, uint64_t(pairs)}) {
            SCOPED_TRACE("radius " + std::to_string(radius) + " cap " + std::to_string(cap));
            params.max_pairs_in_memory = cap;
            Stats stats;
            const std::vector<glm::vec3> out =
                splat_tiled(f.samples, camera, f.photons, params, RenderControl(), stats);
            EXPECT_TRUE(out == reference.actual) << "the output depends on where batches end";
            EXPECT_EQ(counter(stats, "tile_photon_pairs"), pairs);
            EXPECT_EQ(counter(stats, "contributing_pairs"), counter(reference.brute, "contributing_pairs"));
            EXPECT_EQ(counter(stats, "photon_tile_tests"), counter(reference.method, "photon_tile_tests"));
            // Bins: the 2×2 tiles and the groups of samples outside their tile's frustum (seen in the spheres).
            const double bins = counter(stats, "tiles") + counter(stats, "outside_sample_groups");
            EXPECT_GE(counter(stats, "splat_batches"), std::ceil(pairs / std::max(double(cap), bins)));
            // The pair buffers hold 8 bytes a pair (the pairs, then the lists) and the pairs held stay under the
            // cap, but for one photon's pairs (<= bins) per thread while counting and a batch of one photon
            // beyond the cap; add the growth slack of the chunks (512 photons) being counted, and what is per
            // photon (counts, offsets) and per bin.
            const double threads = tbb::this_task_arena::max_concurrency();
            const double photons = double(f.photons.photons.size());
            const double bound = 8.0 * (std::max(double(cap), bins) + threads * bins) +
                                 4.0 * threads * std::min(pairs, 512.0 * bins) + 12.0 * photons + 16.0 * (bins + 1.0) +
                                 24.0 * (photons / 512.0 + 1.0) + 64.0;
            EXPECT_LE(stats.bytes.at("tile_photon_lists"), bound);
            if (cap == uint64_t(pairs)) {
                EXPECT_EQ(counter(stats, "splat_batches"), 1.0);
                EXPECT_EQ(stats.bytes.at("splat_sample_sums"), 0.0);
            } else {
                EXPECT_GE(counter(stats, "splat_batches"), 2.0);
                EXPECT_GT(stats.bytes.at("splat_sample_sums"), 0.0);
            }
            if (cap == 7)
                std::printf("cap 7, r %g: %.0f pairs in %.0f batches, peak %.0f bytes, bit-identical to one batch\n",
                            radius, pairs, counter(stats, "splat_batches"), stats.bytes.at("tile_photon_lists"));
        }
    }
}

// A radius larger than the scene puts every photon in every tile: the default cap still holds them in one batch
// here, a small cap cuts them, and the peak memory follows the cap, not photons × tiles.
TEST(Tiled, RadiusLargerThanTheSceneStaysUnderTheCap) {
    const Camera camera = test::cornell_camera(96, 64);  // 3×2 tiles
    const Frame f = trace_frame(cornell_scene(), camera, 1500, 17);
    SplatParams params = splat_params(1e3f, f.photons);
    params.max_pairs_in_memory = 600;
    Stats stats;
    splat_tiled(f.samples, camera, f.photons, params, RenderControl(), stats);
    const double pairs = counter(stats, "tile_photon_pairs");
    const double bins = 6.0 + counter(stats, "outside_sample_groups");
    EXPECT_EQ(pairs, bins * double(f.photons.photons.size())) << "every photon in every tile and group";
    EXPECT_GE(counter(stats, "splat_batches"), pairs / 600.0);
    EXPECT_LT(stats.bytes.at("tile_photon_lists"), 0.5 * pairs * 8.0);
}

// ---- hand-made samples: off their pixel rays, with and without the flag; origin away from the camera -------

TEST(Tiled, SamplesOffTheirPixelRaysWithOrWithoutTheFlag) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const glm::vec3 eye(1.0e4f, -2.5e3f, 40.0f);
    const int w = 70, h = 50;
    const Camera camera = test::look_at(eye, eye + glm::vec3(0.0f, 10.0f, -1.0f), w, h, 50.0f);
    for (const glm::vec3 origin : {camera.position(), camera.position() + glm::vec3(3.0f, -2.0f, 1.5f)}) {
        ViewSamples vs;
        vs.width = w;
        vs.height = h;
        vs.origin = origin;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (u(rng) < 0.1f) continue;
                const Ray ray = camera.generate_ray(x + 0.5f, y + 0.5f);
                const float depth = 2.0f + 6.0f * u(rng) + ((x / 5 + y / 7) % 2 ? 20.0f : 0.0f);
                ViewSample s{};
                s.position = (ray.origin - origin) + ray.direction * depth;
                s.normal = s.shading_normal = glm::normalize(-ray.direction + 0.5f * random_unit(rng));
                s.wo = -ray.direction;
                s.albedo = glm::vec3(u(rng), u(rng), u(rng));
                s.throughput = glm::vec3(1.0f);
                s.pixel = uint32_t(y * w + x);
                s.depth = depth;
                const float kind = u(rng);
                if (kind < 0.15f) {  // seen through a mirror: anywhere, flagged
                    s.flags = kViaSpecular;
                    s.position = (eye - origin) +
                                 glm::vec3(8.0f * u(rng) - 4.0f, 2.0f + 20.0f * u(rng), 4.0f * u(rng) - 6.0f);
                    s.throughput = glm::vec3(0.3f + u(rng));
                } else if (kind < 0.2f) {  // off the ray, not flagged: the tiles must not trust the flag
                    s.position += glm::vec3(3.0f * u(rng) - 1.5f, 3.0f * u(rng) - 1.5f, 3.0f * u(rng) - 1.5f);
                } else if (kind < 0.21f) {  // behind the camera
                    s.position = (eye - origin) - ray.direction * (1.0f + u(rng));
                }
                vs.samples.push_back(s);
            }
        vs.samples[7].position = glm::vec3(std::numeric_limits<float>::quiet_NaN());  // passes no test anywhere
        PhotonMap map;
        for (int j = 0; j < 2000; ++j) {
            const ViewSample& s = vs.samples[(size_t(j) * 7919u) % vs.samples.size()];
            Photon p{};
            p.position = origin + s.position + random_unit(rng) * (0.4f * u(rng));
            p.normal = u(rng) < 0.8f ? glm::normalize(s.normal + 0.3f * random_unit(rng)) : random_unit(rng);
            p.wi = random_unit(rng);
            if (glm::dot(p.wi, p.normal) < 0.0f) p.wi = -p.wi;
            p.power = glm::vec3(0.5f + u(rng), 0.5f + u(rng), 0.5f + u(rng));
            map.photons.push_back(p);
        }
        map.photons[3].position = glm::vec3(std::numeric_limits<float>::infinity(), 0.0f, 0.0f);
        map.photons[5].position = glm::vec3(0.0f, std::numeric_limits<float>::quiet_NaN(), 0.0f);
        map.photons[9].position = eye + glm::vec3(0.01f, 0.0f, 0.0f);  // at the eye
        map.emitted = 12345;
        for (float radius : {0.05f, 0.3f, 2.0f}) {
            const bool moved = origin != camera.position();
            const std::string what =
                std::string(moved ? "hand-made, moved origin" : "hand-made") + ", r " + std::to_string(radius);
            SCOPED_TRACE(what);
            const Comparison c = compare_with_brute(vs, camera, map, splat_params(radius, map));
            EXPECT_GT(counter(c.method, "samples_outside_tile_frustum"), 0.1 * double(vs.samples.size()));
            EXPECT_TRUE(via_specular_samples_lit(vs, c.expected));
            if (radius == 0.3f) report(what, c);
        }
    }
}

// ---- the screen bounds ------------------------------------------------------------------------------------

// Distance from c to the camera ray through image point (fx, fy), both relative to the camera position: the
// half-line from the eye (perspective) or the whole line (orthographic).
float distance_to_pixel_ray(const Camera& camera, const glm::vec3& c, float fx, float fy) {
    const Ray ray = camera.generate_ray(fx, fy);
    const glm::vec3 o = camera.orthographic() ? ray.origin - camera.position() : glm::vec3(0.0f);
    float t = glm::dot(c - o, ray.direction);
    if (!camera.orthographic()) t = std::max(t, 0.0f);
    return glm::length(c - o - t * ray.direction);
}

TEST(Tiled, ScreenBoundsNeverExcludeAPixelWhoseRayPassesWithinR) {
    std::mt19937 rng(77);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const std::vector<Camera> cameras = {
        test::look_at({0.0f, -4.0f, 1.0f}, {0.0f, 0.0f, 1.0f}, 64, 48, 40.0f),
        shifted_camera({1.0f, -3.0f, 2.0f}, {-0.5f, 1.0f, 0.0f}, 37, 61, 100.0f, 0.4f, -0.3f),
        test::look_at({3.0f, 2.0f, 5.0f}, {0.0f, 0.0f, 0.0f}, 80, 20, 10.0f),
        orthographic_camera({0.0f, -5.0f, 1.0f}, {0.2f, 0.0f, 0.8f}, 50, 40, 1.5f),
    };
    size_t hits = 0, checks = 0, infinite = 0;
    for (const Camera& camera : cameras) {
        const float w = float(camera.width()), h = float(camera.height());
        for (int n = 0; n < 600; ++n) {
            // A centre on a random pixel's ray (sometimes beyond the image, sometimes behind the eye) and a
            // radius from a hair to most of its depth.
            const Ray ray = camera.generate_ray((1.6f * u(rng) - 0.3f) * w, (1.6f * u(rng) - 0.3f) * h);
            const glm::vec3 start = camera.orthographic() ? ray.origin - camera.position() : glm::vec3(0.0f);
            const float t = n % 10 == 0 ? -2.0f * u(rng) : 0.05f + 8.0f * u(rng);
            const glm::vec3 c = start + t * ray.direction + random_unit(rng) * (0.05f * u(rng));
            const float scale = n % 7 == 0 ? 3.0f : 0.5f;
            const float r = std::max(1e-4f, std::fabs(t)) * std::pow(10.0f, -3.0f * u(rng)) * scale;
            const glm::dvec4 b = tiled_sphere_screen_bounds(camera, c, r);
            ASSERT_FALSE(std::isnan(b.x) || std::isnan(b.y) || std::isnan(b.z) || std::isnan(b.w));
            ASSERT_LE(b.x, b.z);
            ASSERT_LE(b.y, b.w);
            infinite += std::isinf(b.x) ? 1 : 0;
            // Image points: uniform, and concentrated around the rectangle's edges where it matters.
            for (int k = 0; k < 300; ++k) {
                float fx, fy;
                if (k % 2 == 0 || std::isinf(b.x)) {
                    fx = w * u(rng), fy = h * u(rng);
                } else {
                    const double ex = k % 4 == 1 ? b.x : b.z, ey = k % 8 < 4 ? b.y : b.w;
                    fx = float(std::clamp(ex + (u(rng) - 0.5) * 4.0, 0.0, double(w)));
                    const double y = k % 3 ? ey : b.y + (b.w - b.y) * u(rng);
                    fy = float(std::clamp(y + (u(rng) - 0.5) * 4.0, 0.0, double(h)));
                }
                if (!(distance_to_pixel_ray(camera, c, fx, fy) < r * (1.0f - 1e-4f))) continue;
                ++hits;
                ++checks;
                EXPECT_TRUE(fx >= b.x && fx <= b.z && fy >= b.y && fy <= b.w)
                    << "camera " << (&camera - cameras.data()) << ": point (" << fx << ", " << fy
                    << ") is within r of the sphere but outside [" << b.x << ", " << b.z << "]×[" << b.y << ", "
                    << b.w << "]";
            }
        }
    }
    EXPECT_GT(hits, 20000u);
    EXPECT_GT(infinite, 10u);
    std::printf("screen bounds: %zu image points within r checked, %zu infinite rectangles\n", checks, infinite);
}

// The rectangle is the tangent-line one, not merely some bound: a sphere on the optical axis of a 90° camera.
TEST(Tiled, ScreenBoundsAreTightOnTheAxis) {
    const Camera camera = test::look_at({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 100, 100, 90.0f);
    const float z = 4.0f, r = 1.0f;
    const glm::dvec4 b = tiled_sphere_screen_bounds(camera, glm::vec3(0.0f, z, 0.0f), r);
    const double half = 50.0 * r / std::sqrt(double(z) * z - double(r) * r);  // tan of the tangent angle × 50 px
    EXPECT_NEAR(b.x, 50.0 - half, 1e-3);
    EXPECT_NEAR(b.z, 50.0 + half, 1e-3);
    EXPECT_NEAR(b.y, 50.0 - half, 1e-3);
    EXPECT_NEAR(b.w, 50.0 + half, 1e-3);
    const glm::dvec4 full = tiled_sphere_screen_bounds(camera, glm::vec3(0.0f, 0.5f, 0.0f), r);
    EXPECT_TRUE(std::isinf(full.x) && std::isinf(full.w)) << "a sphere around the eye covers the screen";
}

// ---- threads, counters, empty input, cancel -----------------------------------------------------------------

TEST(Tiled, ReportsCountersBytesAndStageTimes) {
    const Camera camera = test::cornell_camera(48, 40);
    const Frame f = trace_frame(cornell_scene(), camera, 3000, 23);
    const Comparison c = compare_with_brute(f.samples, camera, f.photons, splat_params(0.1f, f.photons));
    for (const char* name : {"photon_tile_tests", "photon_sample_tests", "contributing_pairs", "tile_photon_pairs"})
        EXPECT_GT(counter(c.method, name), 0.0) << name;
    EXPECT_EQ(counter(c.method, "splat_batches"), 1.0);
    EXPECT_GT(c.method.bytes.at("tile_bounds"), 0.0);
    EXPECT_GT(c.method.bytes.at("tile_photon_lists"), 0.0);
    EXPECT_EQ(c.method.bytes.at("splat_sample_sums"), 0.0) << "one batch keeps no sums between batches";
    EXPECT_GT(c.method.seconds.count("splat_binning"), 0u);
    EXPECT_GT(c.method.seconds.count("splat_shade"), 0u);
    EXPECT_GE(counter(c.method, "photon_sample_tests"), counter(c.method, "contributing_pairs"));
}

TEST(Tiled, RefusesSamplesOfAnotherImage) {
    const Camera camera = test::cornell_camera(40, 30);
    const Frame f = trace_frame(cornell_scene(), camera, 500, 29);
    Stats stats;
    EXPECT_THROW(splat_tiled(f.samples, test::cornell_camera(41, 30), f.photons, splat_params(0.1f, f.photons),
                             RenderControl(), stats),
                 InvalidInput);
    ViewSamples bad = f.samples;
    bad.samples[0].pixel = 40 * 30;
    EXPECT_THROW(splat_tiled(bad, camera, f.photons, splat_params(0.1f, f.photons), RenderControl(), stats),
                 InvalidInput);
    EXPECT_THROW(splat_tiled(f.samples, camera, f.photons, splat_params(0.0f, f.photons), RenderControl(), stats),
                 InvalidInput);
}

// How many samples of all comparisons above were bit-identical to the oracle, printed after the tests.
class BitIdenticalSummary : public ::testing::Environment {
public:
    void TearDown() override {
        if (g_samples > 0)
            std::printf("tiled vs brute: %zu of %zu compared samples bit-identical\n", g_identical, g_samples);
    }
};
::testing::Environment* const g_summary = ::testing::AddGlobalTestEnvironment(new BitIdenticalSummary);

// ---- benchmark (not run by default: --gtest_also_run_disabled_tests --gtest_filter='*Benchmark*') -----------

// CPU time of the calling thread: with a one-thread arena, all the work of a call (the machine is shared, so
// wall times are noisy).
double thread_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// 1920×1080 Cornell box, 200k photons at the default radius: tiled and cluster on the same samples and photons,
// each on one thread (CPU seconds) and on all threads (wall seconds).
TEST(Tiled, DISABLED_Benchmark1080pAgainstCluster) {
    const Camera camera = test::cornell_camera(1920, 1080);
    const Scene& scene = cornell_scene();
    const float diagonal = glm::length(scene.bounds_max() - scene.bounds_min());
    const float radius = 0.015f * diagonal;  // render.cpp's default at 200k photons
    const Frame f = trace_frame(scene, camera, 200000, 1);
    const SplatParams params = splat_params(radius, f.photons);
    std::printf("%zu samples, %zu photons stored, r = %.4f\n", f.samples.samples.size(), f.photons.photons.size(),
                radius);
    auto timed = [](int threads, auto&& body) {  // (CPU s of the calling thread, wall s)
        double cpu = 0.0, wall = 0.0;
        tbb::task_arena(threads).execute([&] {
            const double c0 = thread_cpu_seconds();
            const auto w0 = std::chrono::steady_clock::now();
            body();
            wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
            cpu = thread_cpu_seconds() - c0;
        });
        return std::pair<double, double>(cpu, wall);
    };
    for (int threads : {1, tbb::this_task_arena::max_concurrency()}) {
        Stats cs, ts;
        ClusterHierarchy hierarchy;
        std::vector<glm::vec3> cluster, tiled;
        const auto build = timed(threads, [&] {
            hierarchy = build_cluster_hierarchy(f.samples, ClusterKeyParams::from_camera(camera));
        });
        const auto cluster_time = timed(threads, [&] {
            cluster = splat_cluster(hierarchy, f.samples, f.photons, params, RenderControl(), cs);
        });
        const auto tiled_time = timed(threads, [&] {
            tiled = splat_tiled(f.samples, camera, f.photons, params, RenderControl(), ts);
        });
        size_t different = 0;
        for (size_t i = 0; i < tiled.size(); ++i)
            for (int ch = 0; ch < 3; ++ch)
                different += std::fabs(tiled[i][ch] - cluster[i][ch]) >
                             1e-4f * std::max(std::fabs(tiled[i][ch]), std::fabs(cluster[i][ch]));
        EXPECT_EQ(different, 0u);
        const bool one = threads == 1;
        const double c = one ? cluster_time.first : cluster_time.second, t = one ? tiled_time.first : tiled_time.second;
        const double b = one ? build.first : build.second;
        std::printf("%d thread(s), %s seconds\n", threads, one ? "CPU" : "wall");
        std::printf("  cluster: build %.3f + splat %.3f (traverse %.3f, lists %.3f, shade %.3f); sample tests %.3g, "
                    "contributing %.3g, pairs %.3g\n",
                    b, c, cs.seconds["splat_traverse"], cs.seconds["splat_lists"], cs.seconds["splat_shade"],
                    counter(cs, "photon_sample_tests"), counter(cs, "contributing_pairs"),
                    counter(cs, "leaf_photon_pairs"));
        std::printf("  tiled:   splat %.3f (binning %.3f, shade %.3f); sample tests %.3g, tile tests %.3g, pairs %.3g, "
                    "outside-frustum samples %.0f in %.0f groups; lists %.1f MB, bounds %.2f MB\n",
                    t, ts.seconds["splat_binning"], ts.seconds["splat_shade"], counter(ts, "photon_sample_tests"),
                    counter(ts, "photon_tile_tests"), counter(ts, "tile_photon_pairs"),
                    counter(ts, "samples_outside_tile_frustum"), counter(ts, "outside_sample_groups"),
                    ts.bytes["tile_photon_lists"] / 1e6, ts.bytes["tile_bounds"] / 1e6);
        std::printf("  tiled / cluster: %.2f (cluster with its build: %.2f)\n", t / c, t / (c + b));
    }
}

}  // namespace
