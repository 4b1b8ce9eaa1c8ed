// The approximate directional splat: not equal to brute, but close where it should be and right on average.
// Single-sample nodes at level 0 reproduce brute; a uniformly lit plane averages what brute gives; the Cornell
// box through the whole pipeline stays within a few per cent of brute; the result is the same bit for bit for
// any thread count; facing-away photons never light a sample; zero photons, cancel and level choice behave.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "test_support.h"

namespace ps {
namespace {

using namespace test;

ViewSample diffuse_sample(const glm::vec3& position, const glm::vec3& normal, uint32_t pixel, float depth) {
    ViewSample s{};
    s.position = position;
    s.normal = s.shading_normal = normal;
    s.wo = normal;
    s.albedo = glm::vec3(0.8f, 0.6f, 0.4f);
    s.throughput = glm::vec3(1.0f);
    s.pixel = pixel;
    s.depth = depth;
    return s;
}

// A camera at `origin` looking straight down (−z) at the plane z = −height: one sample per pixel.
ViewSamples plane_view(int width, int plane_height_px, float height) {
    ViewSamples vs;
    vs.width = width;
    vs.height = plane_height_px;
    vs.origin = glm::vec3(120.0f, -35.0f, 7.0f);  // away from 0: everything is splatted relative to it
    for (int y = 0; y < plane_height_px; ++y)
        for (int x = 0; x < width; ++x) {
            const glm::vec3 dir = synthetic_pixel_direction(x, y, width, plane_height_px);
            vs.samples.push_back(diffuse_sample(dir * height, glm::vec3(0, 0, 1), uint32_t(y * width + x), height));
        }
    return vs;
}

glm::vec3 random_upper_hemisphere(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const float z = u(rng), phi = 6.2831853f * u(rng), s = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return glm::vec3(s * std::cos(phi), s * std::sin(phi), z);
}

// `count` photons spread uniformly over the plane z = −height around the view, with margin, from above.
PhotonMap uniform_plane_photons(const ViewSamples& vs, size_t count, float height, float margin, std::mt19937& rng) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const ViewSample& s : vs.samples) lo = glm::min(lo, s.position), hi = glm::max(hi, s.position);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    PhotonMap map;
    for (size_t i = 0; i < count; ++i) {
        Photon p{};
        p.position = vs.origin + glm::vec3(lo.x - margin + (hi.x - lo.x + 2 * margin) * u(rng),
                                           lo.y - margin + (hi.y - lo.y + 2 * margin) * u(rng), -height);
        p.wi = random_upper_hemisphere(rng);
        p.normal = glm::vec3(0, 0, 1);
        p.power = glm::vec3(0.7f + 0.6f * u(rng), 1.0f, 0.5f + u(rng));
        map.photons.push_back(p);
    }
    map.emitted = 3 * count;
    return map;
}

SplatParams directional_params(float radius, const PhotonMap& map, int level = -1, Kernel kernel = Kernel::uniform) {
    SplatParams params;
    params.radius = radius;
    params.emitted = map.emitted;
    params.directional_level = level;
    params.kernel = kernel;
    return params;
}

double luminance_sum(const std::vector<glm::vec3>& v) {
    double sum = 0.0;
    for (const glm::vec3& c : v) sum += double(c.x) + c.y + c.z;
    return sum;
}

// Mean over samples of |a − b| / b, over those where b > 0.
double mean_relative_difference(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    double sum = 0.0;
    size_t lit = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        const double x = double(a[i].x) + a[i].y + a[i].z, y = double(b[i].x) + b[i].y + b[i].z;
        if (y > 0.0) sum += std::fabs(x - y) / y, ++lit;
    }
    return lit ? sum / double(lit) : 0.0;
}

std::vector<glm::vec3> directional(const ViewSamples& vs, const ClusterHierarchy& h, const PhotonMap& map,
                                   const SplatParams& params, Stats& stats) {
    RenderControl control;
    return splat_directional(h, vs, map, params, control, stats);
}

std::vector<glm::vec3> brute(const ViewSamples& vs, const PhotonMap& map, const SplatParams& params) {
    RenderControl control;
    Stats stats;
    return splat_brute(vs, map, params, control, stats);
}

TEST(Directional, UniformlyLitPlaneAveragesWhatBruteGives) {
    const ViewSamples vs = plane_view(96, 64, 4.0f);  // plane about 5.5 × 4.6 units, 8×8-pixel tiles 0.46 wide
    std::mt19937 rng(11);
    const float r = 0.4f;
    const PhotonMap map = uniform_plane_photons(vs, 20000, 4.0f, r, rng);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, key_params(96, 64));
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        const double expected = luminance_sum(brute(vs, map, directional_params(r, map, 0, kernel)));
        // (Level 2 would leave 6 nodes on this small image: a mean of 6 estimates, too noisy to compare.)
        for (int level : {0, 1, -1}) {
            Stats stats;
            const std::vector<glm::vec3> out = directional(vs, h, map, directional_params(r, map, level, kernel), stats);
            const double ratio = luminance_sum(out) / expected;
            std::printf("plane, %s kernel, level %d (used %g): mean / brute's = %.4f\n", to_string(kernel), level,
                        stats.values.at("directional_level"), ratio);
            EXPECT_NEAR(ratio, 1.0, 0.02) << to_string(kernel) << " level " << level;
            EXPECT_EQ(stats.values.at("directional_exact_fallback"), 0.0);
        }
    }
}

// Samples keyed by their 3D position (as if seen through a mirror) each get a leaf of their own: at level 0 every
// node is one sample, its centroid is the sample, and the estimate must be brute's, up to the fixed-point sums
// and the bins (one ωi per bin here: collimated photons), glossy and Epanechnikov included.
TEST(Directional, SingleSampleNodesAtLevelZeroEqualBrute) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ViewSamples vs;
    vs.width = 40;
    vs.height = 30;
    vs.origin = glm::vec3(-300.0f, 12.0f, 45.0f);
    for (uint32_t i = 0; i < 1200; ++i) {
        const glm::vec3 n = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.0f));
        ViewSample s = diffuse_sample(glm::vec3(4.0f * u(rng), 3.0f * u(rng), -5.0f + 0.3f * u(rng)), n, i, 5.0f);
        s.flags = kViaSpecular;
        s.throughput = glm::vec3(0.5f + u(rng));
        s.wo = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.0f));
        if (i % 3 == 0) {
            add_glossy_lobe(vs, s, glm::vec3(0.9f, 0.7f, 0.5f), 0.2f);
        }
        vs.samples.push_back(s);
    }
    const ClusterHierarchy h = build_cluster_hierarchy(vs, key_params(40, 30));
    for (uint32_t leaf : h.leaves) ASSERT_EQ(h.nodes[leaf].sample_end - h.nodes[leaf].sample_begin, 1u);
    PhotonMap map;
    const glm::vec3 wi = glm::normalize(glm::vec3(0.3f, -0.2f, 1.0f));
    for (int i = 0; i < 4000; ++i) {
        Photon p{};
        p.position = vs.origin + glm::vec3(4.0f * u(rng), 3.0f * u(rng), -5.0f + 0.3f * u(rng));
        p.wi = wi;
        p.normal = glm::vec3(0, 0, 1);
        p.power = glm::vec3(u(rng), u(rng), u(rng));
        map.photons.push_back(p);
    }
    map.emitted = 9000;
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        const SplatParams params = directional_params(0.25f, map, 0, kernel);
        const std::vector<glm::vec3> expected = brute(vs, map, params);
        Stats stats;
        const std::vector<glm::vec3> actual = directional(vs, h, map, params, stats);
        ASSERT_EQ(actual.size(), expected.size());
        size_t lit = 0;
        for (size_t i = 0; i < actual.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(actual[i][c], expected[i][c], 1e-5f * std::fabs(expected[i][c]) + 1e-12f)
                    << "sample " << i << " channel " << c << " " << to_string(kernel);
                lit += expected[i][c] > 0.0f;
            }
        EXPECT_GT(lit, actual.size());
    }
}

// Level 0 on a plane: the smaller the nodes relative to r, the closer each sample is to brute's estimate.
TEST(Directional, LevelZeroApproachesBruteAsNodesShrinkRelativeToR) {
    const ViewSamples vs = plane_view(96, 64, 4.0f);  // a tile is about 0.46 units across
    std::mt19937 rng(13);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, key_params(96, 64));
    double previous = INFINITY;
    for (float r : {0.3f, 0.8f, 2.0f}) {
        const PhotonMap map = uniform_plane_photons(vs, 8000, 4.0f, r, rng);
        const SplatParams params = directional_params(r, map, 0);
        Stats stats;
        const double error = mean_relative_difference(directional(vs, h, map, params, stats), brute(vs, map, params));
        std::printf("plane, r = %.1f: mean per-sample relative difference to brute %.4f\n", r, error);
        EXPECT_LT(error, previous);
        previous = error;
    }
    EXPECT_LT(previous, 0.05);
}

RenderResult render_cornell(SplatMethod method, int level, float radius, int size = 64) {
    RenderSettings settings = method_settings(method, 20000, 3);
    settings.radius = radius;
    settings.directional_level = level;
    settings.direct_samples = 1;
    return render_cornell_box(settings, size, size);
}

TEST(Directional, CornellBoxStaysCloseToBrute) {
    const float r = 0.3f;  // a leaf (8×8 of 64² pixels) is about as wide as r
    const RenderResult exact = render_cornell(SplatMethod::brute, -1, r);
    double exact_sum = 0.0;
    for (float v : exact.film[ps::FilmOutput::indirect]) exact_sum += v;
    ASSERT_GT(exact_sum, 0.0);
    for (int level : {0, 1, -1}) {
        const RenderResult approx = render_cornell(SplatMethod::directional, level, r);
        double sum = 0.0, difference = 0.0;
        for (size_t i = 0; i < approx.film[ps::FilmOutput::indirect].size(); ++i) {
            const float v = approx.film[ps::FilmOutput::indirect][i];
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << "component " << i << " = " << v;
            sum += v;
            difference += std::fabs(v - exact.film[ps::FilmOutput::indirect][i]);
        }
        std::printf("Cornell box 64², r = %.2f, level %d (used %g): mean indirect / brute's = %.4f, "
                    "Σ|difference| / Σ brute = %.4f\n",
                    r, level, approx.stats.values.at("directional_level"), sum / exact_sum, difference / exact_sum);
        EXPECT_NEAR(sum / exact_sum, 1.0, level == 1 ? 0.15 : 0.1) << "level " << level;
        EXPECT_LT(difference / exact_sum, level == 1 ? 0.3 : 0.2) << "level " << level;
    }
}

TEST(Directional, AutoLevelFallsBackToExactWhenLeavesAreMuchLargerThanR) {
    // 48² pixels: a leaf's 8×8 pixels span about half a unit of the box, ten times r.
    const RenderResult exact = render_cornell(SplatMethod::brute, -1, 0.05f, 48);
    const RenderResult approx = render_cornell(SplatMethod::directional, -1, 0.05f, 48);
    EXPECT_EQ(approx.stats.values.at("directional_exact_fallback"), 1.0);
    ASSERT_EQ(exact.film[ps::FilmOutput::indirect].size(), approx.film[ps::FilmOutput::indirect].size());
    for (size_t i = 0; i < exact.film[ps::FilmOutput::indirect].size(); ++i)
        EXPECT_NEAR(approx.film[ps::FilmOutput::indirect][i], exact.film[ps::FilmOutput::indirect][i], 1e-4f * std::fabs(exact.film[ps::FilmOutput::indirect][i]) + 1e-9f);
}

ViewSamples random_planes_view(std::mt19937& rng, int width, int height) {
    ViewSamples vs;
    vs.width = width;
    vs.height = height;
    vs.origin = glm::vec3(50.0f, 20.0f, -10.0f);
    const std::vector<Plane> planes = random_planes(rng, 4, 2.0f, 12.0f);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const glm::vec3 dir = synthetic_pixel_direction(x, y, width, height);
            const auto [t, normal] = nearest_plane(planes, dir);
            if (std::isfinite(t)) vs.samples.push_back(diffuse_sample(dir * t, normal, uint32_t(y * width + x), t));
        }
    return vs;
}

PhotonMap photons_near_samples(const ViewSamples& vs, size_t count, float spread, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    PhotonMap map;
    for (size_t i = 0; i < count; ++i) {
        const ViewSample& s = vs.samples[size_t(u(rng) * float(vs.samples.size())) % vs.samples.size()];
        Photon p{};
        p.position = vs.origin + s.position + spread * glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f);
        p.normal = s.normal;
        p.wi = random_upper_hemisphere(rng);
        if (glm::dot(p.wi, p.normal) < 0.0f) p.wi = -p.wi;
        p.power = glm::vec3(0.5f + u(rng), 0.5f + u(rng), 0.5f + u(rng));
        map.photons.push_back(p);
    }
    map.emitted = 2 * count;
    return map;
}

// Flat cut nodes are described from the leaves' summaries (ClusterBuildOptions::leaf_summaries) instead of their
// samples. The facet is the same (centroid, axis, sample count) and its bounds only wider, so the image barely
// moves; nodes across a crease split by whole leaf parts (a leaf across it is summarised as parts split by
// orientation), unless a leaf holds more orientations than it has parts.
// plane_view(width, 64, 3) with the samples of columns x ≥ from_x facing normals[x − from_x] (the last of them from
// there on) instead of the camera.
ViewSamples folded_plane_view(int width, uint32_t from_x, const std::vector<glm::vec3>& normals) {
    ViewSamples vs = plane_view(width, 64, 3.0f);
    for (ViewSample& sample : vs.samples) {
        const uint32_t x = sample.pixel % uint32_t(width);
        if (x < from_x) continue;
        const glm::vec3 n = normals[std::min<size_t>(x - from_x, normals.size() - 1)];
        sample.normal = sample.shading_normal = sample.wo = n;
    }
    return vs;
}

TEST(Directional, LeafSummariesDescribeFlatNodesAsTheSamplesDo) {
    std::mt19937 rng(41);
    ClusterBuildOptions with_summaries;
    with_summaries.leaf_summaries = true;
    struct Case {
        const char* name;
        ViewSamples vs;
        PhotonMap map;
    };
    std::vector<Case> cases;
    {
        ViewSamples plane = plane_view(96, 64, 3.0f);
        PhotonMap map = uniform_plane_photons(plane, 20000, 3.0f, 0.5f, rng);
        cases.push_back({"plane", std::move(plane), std::move(map)});
        ViewSamples planes = random_planes_view(rng, 96, 80);
        PhotonMap near = photons_near_samples(planes, 6000, 0.6f, rng);
        cases.push_back({"random planes", std::move(planes), std::move(near)});
        // Each of these lit by 20000 photons spread evenly over the plane.
        const auto add_lit = [&](const char* name, ViewSamples vs) {
            PhotonMap lit = uniform_plane_photons(vs, 20000, 3.0f, 0.5f, rng);
            cases.push_back({name, std::move(vs), std::move(lit)});
        };
        // A crease down the middle, inside a column of tiles (x = 50 of 100): its leaves come in two parts.
        add_lit("crease", folded_plane_view(100, 50, {{0.6f, 0.0f, 0.8f}}));
        // Five orientations inside one column of tiles (x = 48, 49, 50, 51, then 52 onwards): a leaf's four parts
        // cannot hold them apart, so the nodes over that column read their samples.
        add_lit("five orientations", folded_plane_view(100, 49, {{0.6f, 0.0f, 0.8f}, {0.0f, 0.6f, 0.8f},
                                                                 {-0.6f, 0.0f, 0.8f}, {0.0f, -0.6f, 0.8f}}));
        // A sharper crease (53°: 27° from the mean, past kSplitAngle) on a tile boundary (x = 48 of 96): every
        // leaf is flat, nodes across it split by leaves.
        add_lit("tile-aligned crease", folded_plane_view(96, 48, {{0.8f, 0.0f, 0.6f}}));
    }
    for (const Case& c : cases) {
        const ClusterHierarchy plain = build_cluster_hierarchy(c.vs, key_params(c.vs.width, c.vs.height));
        const ClusterHierarchy summarised =
            build_cluster_hierarchy(c.vs, key_params(c.vs.width, c.vs.height), with_summaries);
        ASSERT_EQ(summarised.leaf_summary_begin.size(), summarised.leaves.size() + 1);
        ASSERT_EQ(summarised.leaf_summaries.size(), summarised.leaf_summary_begin.back());
        for (int level : {0, 1, 2}) {
            SplatParams params = directional_params(0.3f, c.map, level);
            params.plane_distance_factor = 0.2f;
            Stats plain_stats, summarised_stats;
            const std::vector<glm::vec3> a = directional(c.vs, plain, c.map, params, plain_stats);
            const std::vector<glm::vec3> b = directional(c.vs, summarised, c.map, params, summarised_stats);
            const double flat = summarised_stats.counters.at("directional_summarised_cut_nodes");
            const double cut = summarised_stats.counters.at("directional_cut_nodes");
            EXPECT_EQ(plain_stats.counters.at("directional_summarised_cut_nodes"), 0.0);
            EXPECT_GT(flat, 0.0) << c.name << " level " << level;
            if (std::string(c.name) == "crease") EXPECT_EQ(flat, cut) << "level " << level;
            if (std::string(c.name) == "five orientations") EXPECT_LT(flat, cut) << "level " << level;
            if (std::string(c.name) == "tile-aligned crease") {
                EXPECT_EQ(flat, cut) << "level " << level;
                if (level == 2)  // nodes of 4×4 tiles (x tiles 4–7) hold both sides: split
                    EXPECT_GT(summarised_stats.counters.at("directional_facets"), cut);
                EXPECT_EQ(summarised_stats.counters.at("directional_facets"),
                          plain_stats.counters.at("directional_facets")) << "level " << level;
            }
            EXPECT_EQ(plain_stats.counters.at("directional_cut_nodes"), cut);
            const double sum_ratio = luminance_sum(b) / luminance_sum(a);
            const double difference = mean_relative_difference(b, a);
            std::printf("%s, level %d: %.0f of %.0f cut nodes from summaries; Σ ratio %.5f, mean |Δ|/x %.5f\n",
                        c.name, level, flat, cut, sum_ratio, difference);
            EXPECT_NEAR(sum_ratio, 1.0, 0.01) << c.name << " level " << level;
            EXPECT_LT(difference, 0.02) << c.name << " level " << level;
            for (const glm::vec3& v : b) ASSERT_TRUE(std::isfinite(v.x) && v.x >= 0.0f);
        }
    }
}

TEST(Directional, AutoLevelIsAFixedLevelAndHighLevelsClampToTheRoot) {
    std::mt19937 rng(31);
    const ViewSamples vs = random_planes_view(rng, 96, 80);
    const PhotonMap map = photons_near_samples(vs, 3000, 0.6f, rng);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, key_params(96, 80));
    const float r = 2.5f;  // nodes of a few levels fit inside r: the automatic level is above 0
    Stats auto_stats;
    const std::vector<glm::vec3> automatic = directional(vs, h, map, directional_params(r, map, -1), auto_stats);
    const int level = int(auto_stats.values.at("directional_level"));
    EXPECT_GE(level, 1);
    EXPECT_EQ(auto_stats.values.at("directional_exact_fallback"), 0.0);
    Stats fixed_stats;
    EXPECT_EQ(automatic, directional(vs, h, map, directional_params(r, map, level), fixed_stats));
    // A larger radius never picks a lower level.
    Stats larger;
    directional(vs, h, map, directional_params(2.0f * r, map, -1), larger);
    EXPECT_GE(larger.values.at("directional_level"), double(level));
    // Beyond the root's height the whole image is one node.
    Stats top, beyond;
    const std::vector<glm::vec3> at_64 = directional(vs, h, map, directional_params(r, map, 64), beyond);
    EXPECT_EQ(beyond.counters.at("directional_cut_nodes"), 1.0);
    EXPECT_EQ(at_64, directional(vs, h, map, directional_params(r, map, int(beyond.values.at("directional_level"))), top));
    EXPECT_LE(beyond.values.at("directional_level"), double(h.depth));
}

// A strip bent around the y axis (normals from −75° to +75° in x) lit by photons all arriving from +x, slightly
// below the horizon of the unbent strip: only samples whose normal faces ωi may receive light. The strip's
// nodes have wide cones, so photons get past the node tests and it is the bins' facing test that decides.
TEST(Directional, PhotonsFacingAwayDoNotLightASample) {
    ViewSamples vs;
    vs.width = 64;
    vs.height = 16;
    vs.origin = glm::vec3(0.0f);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 64; ++x) {
            const float angle = (float(x) / 63.0f - 0.5f) * 2.0f * 1.309f;  // ±75°
            const glm::vec3 n(std::sin(angle), 0.0f, std::cos(angle));
            const glm::vec3 position = glm::vec3(0.0f, 0.1f * float(y), -5.0f) + 0.5f * n;
            vs.samples.push_back(diffuse_sample(position, n, uint32_t(y * 64 + x), 5.0f));
        }
    const ClusterHierarchy h = build_cluster_hierarchy(vs, key_params(64, 16));
    const glm::vec3 wi = glm::normalize(glm::vec3(1.0f, 0.0f, -0.15f));
    PhotonMap map;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 3000; ++i) {
        const ViewSample& s = vs.samples[size_t(u(rng) * 1023.0f)];
        Photon p{};
        p.position = s.position + 0.05f * glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f);
        p.wi = wi;
        p.normal = s.normal;
        p.power = glm::vec3(1.0f);
        map.photons.push_back(p);
    }
    map.emitted = 3000;
    for (int level : {0, 1, 2}) {
        SplatParams params = directional_params(0.4f, map, level);
        params.cos_normal_tolerance = -1.0f;  // keep every photon up to the facing test
        Stats stats;
        const std::vector<glm::vec3> out = directional(vs, h, map, params, stats);
        size_t lit = 0;
        for (size_t i = 0; i < out.size(); ++i) {
            if (glm::dot(vs.samples[i].normal, wi) <= 0.0f)
                EXPECT_EQ(out[i], glm::vec3(0.0f)) << "sample " << i << " faces away, level " << level;
            else
                lit += out[i].x > 0.0f;
        }
        EXPECT_GT(lit, out.size() / 4) << "level " << level;
    }
}

TEST(Directional, ReportsCountersAndBins) {
    const ViewSamples vs = plane_view(64, 48, 3.0f);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, key_params(64, 48));
    std::mt19937 rng(7);
    const PhotonMap map = uniform_plane_photons(vs, 2000, 3.0f, 0.3f, rng);
    Stats stats;
    directional(vs, h, map, directional_params(1.0f, map, 0), stats);
    EXPECT_EQ(stats.counters.at("photon_sample_tests"), 0.0);
    EXPECT_GT(stats.counters.at("node_deposits"), double(map.photons.size()));
    EXPECT_GE(stats.counters.at("photon_node_tests"), stats.counters.at("node_deposits"));
    EXPECT_GT(stats.counters.at("contributing_pairs"), stats.counters.at("node_deposits"));
    EXPECT_EQ(stats.counters.at("directional_cut_nodes"), double(h.leaves.size()));  // a plane: one facet each
    EXPECT_EQ(stats.counters.at("directional_facets"), double(h.leaves.size()));
    EXPECT_EQ(stats.bytes.at("direction_bins"), double(h.leaves.size() * 8 * 6 * sizeof(int64_t)));
    EXPECT_GT(stats.seconds.at("splat_traverse"), 0.0);
    EXPECT_GT(stats.seconds.at("splat_shade"), 0.0);
    EXPECT_THROW(directional(vs, h, map, directional_params(-1.0f, map, 0), stats), InvalidInput);
}

}  // namespace
}  // namespace ps
