// The cluster_cone method (Moreau et al. 2016, "cluster-trivial"): the normal cones of the hierarchy, the
// conservative node tests of the traversal checked against the per-sample test by brute-force sampling, and the
// splat itself, which must equal the brute-force oracle on random scenes, the Cornell box and the hard cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

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

namespace ps {
namespace {

using namespace test;

constexpr double kPi = 3.14159265358979323846;

// A unit vector perpendicular to unit a.
glm::dvec3 perpendicular(const glm::dvec3& a, std::mt19937& rng) {
    for (;;) {
        const glm::dvec3 v = glm::cross(a, glm::dvec3(random_unit(rng)));
        if (glm::length(v) > 1e-3) return glm::normalize(v);
    }
}

// a turned by `angle` towards the unit perpendicular u.
glm::dvec3 tilt(const glm::dvec3& a, const glm::dvec3& u, double angle) {
    return std::cos(angle) * a + std::sin(angle) * u;
}

double angle_between(const glm::dvec3& a, const glm::dvec3& b) {
    return std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0, 1.0));
}

double cone_angle(const NormalCone& cone) {
    return cone.full() ? kPi : std::atan2(double(cone.sin_angle), double(cone.cos_angle));
}

// Whether the cone holds direction d with at least `slack` radians to spare.
bool cone_holds(const NormalCone& cone, const glm::vec3& d, double slack) {
    if (cone.full()) return true;
    return angle_between(glm::dvec3(cone.axis), glm::dvec3(d)) + slack <= cone_angle(cone);
}

// Directions around a random centre: `boundary` of them exactly at `spread` (evenly around it, so the cone's
// edge is reached in every direction), the rest anywhere inside; lengths off 1 by up to 1e-6 as floats are.
std::vector<glm::vec3> direction_set(std::mt19937& rng, double spread, int boundary, int inside) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const glm::dvec3 centre(random_unit(rng));
    const glm::dvec3 e1 = perpendicular(centre, rng), e2 = glm::cross(centre, e1);
    std::vector<glm::vec3> out;
    for (int i = 0; i < boundary; ++i) {
        const double phi = 2.0 * kPi * (i + u(rng) * 0.1) / std::max(boundary, 1);
        out.push_back(glm::vec3(tilt(centre, std::cos(phi) * e1 + std::sin(phi) * e2, spread)));
    }
    for (int i = 0; i < inside; ++i) {
        const double phi = 2.0 * kPi * u(rng);
        out.push_back(glm::vec3(tilt(centre, std::cos(phi) * e1 + std::sin(phi) * e2, spread * u(rng))));
    }
    return out;
}

// ---- cones ------------------------------------------------------------------------------------------------

TEST(NormalCones, LeafConeHoldsEveryDirectionWithItsSlack) {
    std::mt19937 rng(1);
    int narrow = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        const double spread = trial % 5 == 0 ? 0.0 : std::pow(10.0, -6.0 + 6.5 * (trial % 97) / 96.0);  // to ~3 rad
        const std::vector<glm::vec3> set = direction_set(rng, std::min(spread, 3.1), 1 + trial % 9, trial % 7);
        const NormalCone cone = cone_of_directions(set);
        for (const glm::vec3& d : set) ASSERT_TRUE(cone_holds(cone, d, 5e-5)) << "trial " << trial;
        if (spread < 0.5) {
            EXPECT_FALSE(cone.full());
            // Around the mean direction, θ is at most twice the set's own angular radius.
            EXPECT_LE(cone_angle(cone), 2.0 * spread + 2e-4) << "trial " << trial << ": needlessly wide";
            ++narrow;
        }
    }
    EXPECT_GT(narrow, 1000);
    // One direction: θ is the slack alone. Opposite directions: no useful axis, the full cone. None: full.
    const NormalCone one = cone_of_directions({glm::vec3(0, 0, 1)});
    EXPECT_NEAR(cone_angle(one), 1e-4, 1e-6);
    EXPECT_TRUE(cone_of_directions({glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)}).full());
    EXPECT_TRUE(cone_of_directions({}).full());
    EXPECT_TRUE(cone_of_directions({glm::vec3(0, 0, 1), glm::vec3(NAN, 0, 0)}).full());
}

TEST(NormalCones, MergedConeHoldsEveryInputDirection) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 2000; ++trial) {
        // A chain of merges, as up a tree: every direction of every input stays inside.
        std::vector<glm::vec3> all;
        NormalCone merged;
        const int inputs = 2 + trial % 7;
        for (int k = 0; k < inputs; ++k) {
            const std::vector<glm::vec3> set = direction_set(rng, 1.5 * u(rng) * u(rng), 4, 3);
            const NormalCone cone = cone_of_directions(set);
            merged = k == 0 ? cone : merge_cones(merged, cone);
            all.insert(all.end(), set.begin(), set.end());
            for (const glm::vec3& d : all) ASSERT_TRUE(cone_holds(merged, d, 5e-5)) << "trial " << trial;
        }
    }
    // A cone inside another merges to the outer one; nearly opposite cones merge to the full cone.
    const NormalCone wide = cone_of_directions(direction_set(rng, 0.8, 16, 0));
    const NormalCone narrow = cone_of_directions({wide.axis});
    EXPECT_NEAR(cone_angle(merge_cones(wide, narrow)), cone_angle(wide), 2e-6);
    const NormalCone up = cone_of_directions({glm::vec3(0, 0, 1), glm::vec3(0.1f, 0, 0.995f)});
    const NormalCone down = cone_of_directions({glm::vec3(0, 0, -1), glm::vec3(-0.1f, 0, -0.995f)});
    EXPECT_TRUE(merge_cones(up, down).full());
}

// ---- node tests against the per-sample test ------------------------------------------------------------

// The per-sample facing and orientation tests exactly as splat.h computes them.
bool sample_faces(const glm::vec3& n, const glm::vec3& wi) { return glm::dot(n, wi) > 0.0f; }
bool sample_oriented(const glm::vec3& n, const glm::vec3& np, float cos_tau) { return glm::dot(n, np) > cos_tau; }

TEST(ConeTests, RejectsAndAcceptsAgreeWithThePerSampleTest) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> g;
    int rejects_facing = 0, accepts_facing = 0, rejects_orientation = 0, accepts_orientation = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const double spread = trial % 11 == 0 ? 0.0 : 1.6 * u(rng) * u(rng);
        const std::vector<glm::vec3> normals = direction_set(rng, spread, 24, 8);
        const NormalCone cone = cone_of_directions(normals);
        const glm::dvec3 axis(cone.axis);
        double widest = 0.0;  // the normals' own largest angle to the axis (the cone adds its slack to it)
        for (const glm::vec3& n : normals) widest = std::max(widest, angle_between(axis, glm::dvec3(n)));
        for (int q = 0; q < 16; ++q) {
            // Photon directions and normals placed near the critical angles π/2 ± θ, τ ± θ (θ that of the cone
            // or that of the normals themselves), some at random.
            const double theta = q % 3 == 0 ? cone_angle(cone) : widest;
            const glm::dvec3 side = perpendicular(axis, rng);
            const double jitter = g(rng) * std::pow(10.0, -7.0 + 6.0 * u(rng));
            const double facing_angle = q % 4 == 3 ? kPi * u(rng) : kPi / 2 + (q % 2 ? theta : -theta) + jitter;
            const double cos_tau = q % 8 == 7 ? -1.0 + 2.0 * u(rng) : std::cos(kPi * u(rng));
            const double tau = std::acos(cos_tau);
            const double normal_angle = q % 4 == 2 ? kPi * u(rng) : tau + (q % 2 ? theta : -theta) + jitter;
            const float length = q % 3 == 0 ? float(0.25 + 3.0 * u(rng)) : 1.0f;  // photon normals of any length
            const glm::vec3 wi(tilt(axis, side, std::clamp(facing_angle, 0.0, kPi)));
            const glm::vec3 np =
                length * glm::vec3(tilt(axis, perpendicular(axis, rng), std::clamp(normal_angle, 0.0, kPi)));
            const cone_tests::PhotonCone pc = cone_tests::photon_cone(wi, np, float(cos_tau));
            const bool r2 = cone_tests::faces_away(cone, pc), a2 = cone_tests::faces_photon(cone, pc);
            const bool r3 = cone_tests::misoriented(cone, pc), a3 = cone_tests::oriented(cone, pc);
            ASSERT_FALSE(r2 && a2);
            ASSERT_FALSE(r3 && a3);
            for (const glm::vec3& unit : normals)
                for (float scale : {1.0f, 1.0f + 0.99e-4f, 1.0f - 0.99e-4f}) {  // as long as kNodeRegular allows
                    const glm::vec3 n = unit * scale;
                    if (r2) ASSERT_FALSE(sample_faces(n, wi)) << "R2 dropped a facing normal, trial " << trial;
                    if (a2) ASSERT_TRUE(sample_faces(n, wi)) << "A2 took a normal facing away, trial " << trial;
                    if (r3) ASSERT_FALSE(sample_oriented(n, np, float(cos_tau))) << "R3 dropped one, trial " << trial;
                    if (a3) ASSERT_TRUE(sample_oriented(n, np, float(cos_tau))) << "A3 took one, trial " << trial;
                }
            rejects_facing += r2;
            accepts_facing += a2;
            rejects_orientation += r3;
            accepts_orientation += a3;
        }
    }
    std::printf("R2 %d, A2 %d, R3 %d, A3 %d of %d\n", rejects_facing, accepts_facing, rejects_orientation,
                accepts_orientation, 4000 * 16);
    // Not vacuous: each test fires often, right at its limit too.
    EXPECT_GT(rejects_facing, 5000);
    EXPECT_GT(accepts_facing, 5000);
    EXPECT_GT(rejects_orientation, 5000);
    EXPECT_GT(accepts_orientation, 5000);
}

TEST(ConeTests, DegenerateAndExtremePhotons) {
    const NormalCone cone = cone_of_directions({glm::vec3(0, 0, 1), glm::vec3(0, 0.1f, 0.995f)});
    // Zero or NaN ωi / n_p: nothing is rejected or accepted on their account.
    for (const glm::vec3& bad : {glm::vec3(0.0f), glm::vec3(NAN, 0, 1), glm::vec3(INFINITY, 0, 0)}) {
        const cone_tests::PhotonCone pc = cone_tests::photon_cone(bad, bad, 0.5f);
        EXPECT_FALSE(cone_tests::faces_away(cone, pc));
        EXPECT_FALSE(cone_tests::faces_photon(cone, pc));
        EXPECT_FALSE(cone_tests::misoriented(cone, pc));
        EXPECT_FALSE(cone_tests::oriented(cone, pc));
    }
    // cos τ > 1 (+ length tolerance): no normal passes; cos τ < −1: every normal passes; NaN: no conclusion.
    // cos τ = 1 exactly rejects nothing: a normal of length 1 + 1e-4 could pass.
    const glm::vec3 up(0, 0, 1);
    EXPECT_TRUE(cone_tests::misoriented(cone, cone_tests::photon_cone(up, up, 1.001f)));
    EXPECT_FALSE(cone_tests::misoriented(cone, cone_tests::photon_cone(up, up, 1.0f)));
    EXPECT_TRUE(cone_tests::oriented(cone, cone_tests::photon_cone(up, up, -1.5f)));
    EXPECT_FALSE(cone_tests::misoriented(cone, cone_tests::photon_cone(up, up, NAN)));
    EXPECT_FALSE(cone_tests::oriented(cone, cone_tests::photon_cone(up, up, NAN)));
    // The full cone never culls (it may hold normals of any length) and never gives A2.
    const NormalCone full;
    EXPECT_FALSE(cone_tests::misoriented(full, cone_tests::photon_cone(-up, -up, 1.0f)));
    EXPECT_FALSE(cone_tests::faces_away(full, cone_tests::photon_cone(-up, up, 0.5f)));
    EXPECT_FALSE(cone_tests::faces_photon(full, cone_tests::photon_cone(up, up, 0.5f)));
    // The plain cases.
    EXPECT_TRUE(cone_tests::faces_away(cone, cone_tests::photon_cone(-up, up, 0.5f)));
    EXPECT_TRUE(cone_tests::faces_photon(cone, cone_tests::photon_cone(up, up, 0.5f)));
    EXPECT_TRUE(cone_tests::oriented(cone, cone_tests::photon_cone(up, up, 0.5f)));
    EXPECT_TRUE(cone_tests::misoriented(cone, cone_tests::photon_cone(up, -up, 0.5f)));
}

TEST(BoxTests, AcceptedBoxHasNoPointAtDistanceRorMore) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int accepted = 0, near_limit = 0;
    for (int trial = 0; trial < 100000; ++trial) {
        const float scale = std::pow(10.0f, -3.0f + 6.0f * u(rng));
        const glm::vec3 p = scale * (glm::vec3(u(rng), u(rng), u(rng)) * 200.0f - 100.0f);  // far from 0 too
        const glm::vec3 size = scale * glm::vec3(u(rng), u(rng), u(rng)) * (trial % 3 ? 1.0f : 1e-3f);
        const glm::vec3 lo = p + scale * (glm::vec3(u(rng), u(rng), u(rng)) - 0.5f) - 0.5f * size;
        const glm::vec3 hi = lo + size;
        // Radii right at the accept limit for the farthest corner (±a few ulps), and at random.
        const glm::vec3 far = glm::max(glm::abs(p - lo), glm::abs(hi - p));
        float r = trial % 4 == 0 ? scale * 2.0f * u(rng) : glm::length(far) * (1.0f + 1.5e-5f * u(rng));
        for (int k = int(u(rng) * 8.0f) - 4; k > 0; --k) r = std::nextafter(r, INFINITY);
        for (int k = int(u(rng) * 8.0f) - 4; k < 0; ++k) r = std::nextafter(r, 0.0f);
        const float max_d2 = cone_tests::max_distance_sq(p, lo, hi);
        if (!(max_d2 < r * r * (1.0f - 1e-5f))) continue;  // the uniform kernel's accept threshold
        ++accepted;
        near_limit += max_d2 > r * r * 0.9999f;
        for (int k = 0; k < 16; ++k) {
            const glm::vec3 x =
                k < 8 ? glm::vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z)
                      : glm::clamp(lo + glm::vec3(u(rng), u(rng), u(rng)) * (hi - lo), lo, hi);
            const glm::vec3 d = x - p;  // the per-sample distance test, as splat.h computes it
            ASSERT_LT(glm::dot(d, d), r * r) << "trial " << trial;
        }
    }
    EXPECT_GT(accepted, 10000);
    EXPECT_GT(near_limit, 1000);
}

TEST(BoxTests, PlaneDistanceAcceptHoldsForEverySample) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int passed = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        // Samples on a slightly bumpy, tilted patch of a plane through p, normals within a narrow cone.
        const glm::vec3 n0 = trial % 2 ? glm::vec3(0, 0, 1) : random_unit(rng);
        const glm::dvec3 e1 = perpendicular(glm::dvec3(n0), rng), e2 = glm::cross(glm::dvec3(n0), e1);
        const float r = 0.5f + u(rng), kappa = 0.02f + 0.3f * u(rng);
        const glm::vec3 p = glm::vec3(u(rng), u(rng), u(rng)) * 10.0f;
        const float bump = 0.05f * kappa * r * u(rng), spread = 0.1f * u(rng);
        std::vector<glm::vec3> xs, ns;
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (int k = 0; k < 32; ++k) {
            const glm::vec3 x = p + glm::vec3(float(0.6f * r * (u(rng) - 0.5f)) * glm::vec3(e1) +
                                              float(0.6f * r * (u(rng) - 0.5f)) * glm::vec3(e2)) +
                                (u(rng) - 0.5f) * bump * n0 + (trial % 5 == 0 ? 0.5f * kappa * r * n0 : glm::vec3(0));
            xs.push_back(x);
            ns.push_back(glm::normalize(n0 + spread * (glm::vec3(u(rng), u(rng), u(rng)) - 0.5f)));
            lo = glm::min(lo, x);
            hi = glm::max(hi, x);
        }
        const NormalCone cone = cone_of_directions(ns);
        const float max_d2 = cone_tests::max_distance_sq(p, lo, hi);
        if (!(max_d2 < r * r)) continue;
        if (!cone_tests::plane_test_passes(p, lo, hi, cone, max_d2, r, kappa)) continue;
        ++passed;
        for (size_t k = 0; k < xs.size(); ++k)  // splat.h's plane-distance test
            ASSERT_LT(std::fabs(glm::dot(ns[k], xs[k] - p)), kappa * r) << "trial " << trial;
    }
    EXPECT_GT(passed, 2000);
}

// ---- the hierarchy with cones ----------------------------------------------------------------------------

// The synthetic scenes and photons of these tests (test_support.h): planes and photons that nodes may accept.
ViewSamples random_scene(const SyntheticOptions& o, std::mt19937& rng) { return synthetic_view_samples(o, rng); }

PhotonMap random_photons(const ViewSamples& vs, size_t count, float spread, std::mt19937& rng) {
    return synthetic_photons(vs, count, spread, rng, cone_photon_options());
}

// Photons as random_photons gives, all on surfaces facing +z and arriving from above: nodes on planes facing the
// camera accept them whole.
PhotonMap photons_from_above(const ViewSamples& vs, size_t count, float spread, std::mt19937& rng) {
    PhotonMap map = random_photons(vs, count, spread, rng);
    for (Photon& p : map.photons) p.normal = glm::vec3(0, 0, 1), p.wi = glm::normalize(p.wi + glm::vec3(0, 0, 2));
    return map;
}

ClusterHierarchy build_with_cones(const ViewSamples& vs, const ClusterKeyParams& key) {
    ClusterBuildOptions options;
    options.normal_cones = true;
    return build_cluster_hierarchy(vs, key, options);
}

TEST(ClusterHierarchyCones, ConesHoldEveryNormalOfTheirSubtreeAndFlagsAreExact) {
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        std::mt19937 rng(seed);
        SyntheticOptions o = cone_scene_options();
        o.width = 64 + 16 * int(seed);
        o.height = 48;
        o.glossy_fraction = 0.05;
        ViewSamples vs = random_scene(o, rng);
        vs.samples[7].normal *= 2.0f;  // not unit: full cones up its chain, not regular
        vs.samples[20].position.x = NAN;
        const ClusterKeyParams key = key_params(o.width, o.height);
        const ClusterHierarchy plain = build_cluster_hierarchy(vs, key);
        const ClusterHierarchy h = build_with_cones(vs, key);
        EXPECT_FALSE(plain.has_cones());
        EXPECT_TRUE(plain.cones.empty());
        EXPECT_EQ(plain.cone_bytes(), 0u);
        ASSERT_TRUE(h.has_cones());
        EXPECT_EQ(h.bytes(), plain.bytes());
        EXPECT_GE(h.cone_bytes(), h.nodes.size() * (sizeof(NormalCone) + 1));
        // The same tree, with or without cones.
        ASSERT_EQ(plain.nodes.size(), h.nodes.size());
        EXPECT_EQ(0, std::memcmp(plain.nodes.data(), h.nodes.data(), h.nodes.size() * sizeof(ClusterNode)));
        EXPECT_EQ(plain.sample_order, h.sample_order);
        const uint32_t at7 =
            uint32_t(std::find(h.sample_order.begin(), h.sample_order.end(), 7u) - h.sample_order.begin());
        size_t narrow = 0;
        for (size_t i = 0; i < h.nodes.size(); ++i) {
            const ClusterNode& node = h.nodes[i];
            const NormalCone& cone = h.cones[i];
            bool diffuse = true, regular = true;
            for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
                const ViewSample& s = vs.samples[h.sample_order[k]];
                ASSERT_TRUE(cone_holds(cone, s.normal, 5e-5)) << "node " << i;
                diffuse = diffuse && !(s.flags & kGlossy);
                regular = regular && std::fabs(glm::length(s.normal) - 1.0f) < 1e-4f && std::isfinite(s.position.x);
            }
            EXPECT_EQ(bool(h.node_flags[i] & kNodeDiffuseOnly), diffuse) << "node " << i;
            EXPECT_EQ(bool(h.node_flags[i] & kNodeRegular), regular) << "node " << i;
            if (node.sample_begin <= at7 && at7 < node.sample_end) EXPECT_TRUE(cone.full()) << "node " << i;
            // A parent's cone holds its children's: θ never shrinks towards the root.
            for (uint32_t c = node.first_child; c != node.first_child + node.child_count; ++c)
                EXPECT_GE(cone_angle(cone) + 1e-6, cone_angle(h.cones[c]));
            narrow += cone_angle(cone) < 0.01 ? 1 : 0;
        }
        EXPECT_GT(narrow, h.leaves.size() / 2) << "leaves on a plane have (nearly) zero-width cones";
    }
}

// ---- the splat --------------------------------------------------------------------------------------------

struct Outcome {
    Stats brute, cone, cluster;
};

// cluster_cone against brute (1e-4 relative per sample and channel) and against cluster (never more tests).
Outcome compare(const ViewSamples& vs, const PhotonMap& map, const SplatParams& params, const ClusterKeyParams& key,
                const char* what) {
    Outcome o;
    const ClusterHierarchy h = build_with_cones(vs, key);
    // The same pairs contribute (accepted ones counted too): test::compare_with_brute.
    const Comparison c = compare_with_brute(SplatMethod::cluster_cone, {vs, &h}, map, params, what);
    o.brute = c.brute;
    o.cone = c.method;
    splat_cluster(h, vs, map, params, RenderControl(), o.cluster);
    // Cones only ever remove tests.
    EXPECT_LE(counter(o.cone, "photon_sample_tests"), counter(o.cluster, "photon_sample_tests")) << what;
    EXPECT_LE(counter(o.cone, "accepted_samples"), counter(o.cone, "contributing_pairs")) << what;
    return o;
}

void report(const char* what, const Outcome& o) {
    const double contributing = counter(o.brute, "contributing_pairs");
    std::printf("%-34s contributing %9.0f | accepts %7.0f (%8.0f samples) | sample tests cluster %9.0f, "
                "cone %9.0f | rejects dist %.0f facing %.0f orient %.0f\n",
                what, contributing, counter(o.cone, "node_accepts"), counter(o.cone, "accepted_samples"),
                counter(o.cluster, "photon_sample_tests"), counter(o.cone, "photon_sample_tests"),
                counter(o.cone, "node_rejects_distance"), counter(o.cone, "node_rejects_cone_facing"),
                counter(o.cone, "node_rejects_cone_orientation"));
}

// Samples of `o` and `photons` photons_from_above within `spread` of them, both drawn from `rng`, and the
// comparison of cluster_cone with brute and cluster at `radius` (reported as `what`).
struct FromAbove {
    ViewSamples vs;
    PhotonMap map;
    Outcome out;
};

FromAbove splat_from_above(const SyntheticOptions& o, std::mt19937& rng, size_t photons, float spread, float radius,
                           const char* what) {
    FromAbove f;
    f.vs = random_scene(o, rng);
    f.map = photons_from_above(f.vs, photons, spread, rng);
    f.out = compare(f.vs, f.map, splat_params(radius, f.map), key_params(o.width, o.height), what);
    report(what, f.out);
    return f;
}

// A radius as large as the scene: only the cones sort photons out, so lists of a hundred photons and more meet the
// accepts of the leaves' ancestors in one sample; still brute's sums, and the same bits on any thread count.
TEST(SplatClusterCone, LongLeafListsWithAccepts) {
    std::mt19937 rng(23);
    const ViewSamples vs = random_scene(cone_scene_options(), rng);
    const PhotonMap map = random_photons(vs, 7000, 0.5f, rng);
    const ClusterHierarchy h = build_with_cones(vs, key_params(48, 40));
    const SplatParams params = splat_params(1e3f, map);
    const Outcome out = compare(vs, map, params, key_params(48, 40), "long lists");
    EXPECT_GT(counter(out.cone, "leaf_photon_pairs"), 50.0 * double(h.leaves.size()));
    EXPECT_GT(counter(out.cone, "node_accepts"), 0.0);
    std::vector<glm::vec3> one, two;
    Stats s1, s2;
    RenderControl control;
    tbb::task_arena(1).execute([&] { one = splat_cluster_cone(h, vs, map, params, control, s1); });
    tbb::task_arena(2).execute([&] { two = splat_cluster_cone(h, vs, map, params, control, s2); });
    EXPECT_TRUE(one == two) << "not bit-identical across thread counts";
}

TEST(SplatClusterCone, LargeRadiusAcceptsWholeNodesAndSavesSampleTests) {
    std::mt19937 rng(11);
    SyntheticOptions o = sized(96, 64, cone_scene_options());
    o.specular_fraction = 0.0;
    o.axis_aligned = true;
    o.planes = 2;
    const Outcome out = splat_from_above(o, rng, 1500, 0.2f, 2.0f, "large radius").out;
    EXPECT_GT(counter(out.cone, "node_accepts"), 1000.0);
    EXPECT_GT(counter(out.cone, "accepted_samples"), 0.5 * counter(out.brute, "contributing_pairs"));
    EXPECT_LT(counter(out.cone, "photon_sample_tests"), 0.5 * counter(out.cluster, "photon_sample_tests"));
    EXPECT_GT(out.cone.bytes.at("accepted_flux"), 0.0);
    EXPECT_GT(out.cone.bytes.at("cones"), 0.0);
    EXPECT_GT(out.cone.bytes.at("hierarchy"), 0.0);
    EXPECT_GE(out.cone.bytes.at("leaf_photon_lists"), 0.0);
}

TEST(SplatClusterCone, EpanechnikovKernelStaysExactThroughMoments) {
    for (uint32_t seed = 1; seed <= 2; ++seed) {
        std::mt19937 rng(100 + seed);
        SyntheticOptions o = cone_scene_options();
        o.axis_aligned = seed == 2;
        const ViewSamples vs = random_scene(o, rng);
        const PhotonMap map = random_photons(vs, 2000, 0.5f, rng);
        double accepts = 0.0;
        for (float radius : {0.05f, 0.4f, 2.0f, 1e3f}) {
            SplatParams params = splat_params(radius, map);
            params.kernel = Kernel::epanechnikov;
            const std::string what = "epanechnikov seed " + std::to_string(seed) + " r " + std::to_string(radius);
            const Outcome out = compare(vs, map, params, key_params(48, 40), what.c_str());
            if (radius == 2.0f) report(what.c_str(), out);
            accepts += counter(out.cone, "node_accepts");
        }
        EXPECT_GT(accepts, 100.0);
    }
}

TEST(SplatClusterCone, GlossySamplesAreNeverAccepted) {
    std::mt19937 rng(13);
    SyntheticOptions o = cone_scene_options();
    o.axis_aligned = true;
    o.specular_fraction = 0.0;
    o.glossy_fraction = 0.01;
    const FromAbove f = splat_from_above(o, rng, 2000, 0.3f, 1.0f, "1% glossy");
    const ViewSamples& vs = f.vs;
    const PhotonMap& map = f.map;
    const Outcome& mixed = f.out;
    EXPECT_GT(counter(mixed.cone, "node_accepts"), 0.0);
    // The accepted nodes hold diffuse samples only: count what accepts could reach at most.
    const ClusterHierarchy h = build_with_cones(vs, key_params(48, 40));
    size_t diffuse_only_leaves = 0;
    for (uint32_t leaf : h.leaves) diffuse_only_leaves += h.node_flags[leaf] & kNodeDiffuseOnly ? 1 : 0;
    EXPECT_LT(diffuse_only_leaves, h.leaves.size());
    // All glossy: no accept at all, and still exact.
    ViewSamples glossy = vs;
    for (ViewSample& s : glossy.samples) add_glossy_lobe(glossy, s, glm::vec3(0.5f), 0.2f);
    const Outcome all = compare(glossy, map, splat_params(1.0f, map), key_params(48, 40), "all glossy");
    EXPECT_EQ(counter(all.cone, "node_accepts"), 0.0);
    EXPECT_EQ(counter(all.cone, "accepted_samples"), 0.0);
}

// A smooth-shaded sample takes each photon times (n_s·ω_i)/(n_g·ω_i) of the photon's own triangle
// (photon_shading_normals.h), which a trivial accept's one sum for all photons cannot give: its nodes are never
// accepted, and the splat is still brute's.
TEST(SplatClusterCone, SmoothShadedSamplesAreNeverAccepted) {
    std::mt19937 rng(17);
    SyntheticOptions o = cone_scene_options();
    o.axis_aligned = true;
    o.specular_fraction = 0.0;
    const FromAbove f = splat_from_above(o, rng, 2000, 0.3f, 1.0f, "flat-shaded");
    EXPECT_GT(counter(f.out.cone, "node_accepts"), 0.0);
    ViewSamples smooth = f.vs;
    std::uniform_real_distribution<float> lean(-0.3f, 0.3f);
    for (ViewSample& s : smooth.samples)
        s.shading_normal = glm::normalize(s.normal + glm::vec3(lean(rng), lean(rng), lean(rng)));
    const Outcome out = compare(smooth, f.map, splat_params(1.0f, f.map), key_params(48, 40), "smooth-shaded");
    EXPECT_EQ(counter(out.cone, "node_accepts"), 0.0);
    // The ratios are in brute's sums: the same photons give another image.
    RenderControl control;
    Stats flat_stats, smooth_stats;
    const std::vector<glm::vec3> flat = splat_brute(f.vs, f.map, splat_params(1.0f, f.map), control, flat_stats);
    const std::vector<glm::vec3> leaning = splat_brute(smooth, f.map, splat_params(1.0f, f.map), control, smooth_stats);
    size_t differing = 0;
    for (size_t i = 0; i < flat.size(); ++i) differing += flat[i] != leaning[i] ? 1 : 0;
    EXPECT_GT(differing, flat.size() / 2);
}

// A bump-shadowed sample's diffuse f depends on each photon's direction (bump_shadowing.h), even where its shading
// normal is its triangle's: never accepted, still brute's.
TEST(SplatClusterCone, BumpShadowedSamplesAreNeverAccepted) {
    std::mt19937 rng(23);
    SyntheticOptions o = cone_scene_options();
    o.axis_aligned = true;
    o.specular_fraction = 0.0;
    const FromAbove f = splat_from_above(o, rng, 2000, 0.3f, 1.0f, "flat-shaded");
    EXPECT_GT(counter(f.out.cone, "node_accepts"), 0.0);
    ViewSamples bumped = f.vs;
    std::uniform_real_distribution<float> lean(-0.5f, 0.5f);
    for (ViewSample& s : bumped.samples) {
        s.smooth_normal = glm::normalize(s.normal + glm::vec3(lean(rng), lean(rng), 0.0f));
        s.flags |= kBumpShadowed;
    }
    const Outcome out = compare(bumped, f.map, splat_params(1.0f, f.map), key_params(48, 40), "bump-shadowed");
    EXPECT_EQ(counter(out.cone, "node_accepts"), 0.0);
    RenderControl control;
    Stats flat_stats, bumped_stats;
    const std::vector<glm::vec3> flat = splat_brute(f.vs, f.map, splat_params(1.0f, f.map), control, flat_stats);
    const std::vector<glm::vec3> shadowed = splat_brute(bumped, f.map, splat_params(1.0f, f.map), control, bumped_stats);
    size_t darker = 0;
    for (size_t i = 0; i < flat.size(); ++i) darker += shadowed[i].x < flat[i].x ? 1 : 0;
    EXPECT_GT(darker, flat.size() / 4);
}

TEST(SplatClusterCone, PlaneDistanceTest) {
    for (bool aligned : {true, false}) {
        std::mt19937 rng(17);
        SyntheticOptions o = cone_scene_options();
        o.axis_aligned = aligned;
        const ViewSamples vs = random_scene(o, rng);
        PhotonMap map = random_photons(vs, 2000, 0.4f, rng);
        for (float kappa : {0.05f, 0.2f, 1.5f}) {
            SplatParams params = splat_params(0.6f, map);
            params.plane_distance_factor = kappa;
            params.cos_normal_tolerance = 0.9f;
            const std::string what = std::string(aligned ? "aligned" : "tilted") + " kappa " + std::to_string(kappa);
            const Outcome out = compare(vs, map, params, key_params(48, 40), what.c_str());
            if (aligned && kappa == 0.2f) {
                report(what.c_str(), out);
                EXPECT_GT(counter(out.cone, "node_accepts"), 100.0);
            }
        }
    }
}

// Photons on box faces and corners and at distance r (± an ulp) from boxes and samples, on a grid of samples at
// binary-fraction positions (exact distances), with depth discontinuities inside tiles.
TEST(SplatClusterCone, PhotonsOnBoxFacesAndAtDistanceExactlyR) {
    const ViewSamples vs = binary_grid_samples();
    const ClusterHierarchy h = build_with_cones(vs, key_params(32, 32));
    for (float r : {0.5f, 2.0f}) {
        PhotonMap map;
        auto add = [&](const glm::vec3& position, bool grazing) {
            map.photons.push_back(photon_at(position, grazing ? glm::normalize(glm::vec3(1.0f, 0.0f, 1e-7f))
                                                              : glm::normalize(glm::vec3(0.1f, 0.2f, 1.0f))));
        };
        const float below = std::nextafter(r, 0.0f), above = std::nextafter(r, 1.0f);
        for (const ClusterNode& node : h.nodes) {
            const glm::vec3 lo = node.box_min, hi = node.box_max, mid = 0.5f * (lo + hi);
            add(lo, false);
            add(hi, false);
            add(glm::vec3(lo.x, mid.y, mid.z), false);
            add(glm::vec3(mid.x, hi.y, mid.z), true);
            for (float d : {below, r, above}) {
                add(glm::vec3(hi.x + d, mid.y, mid.z), false);
                add(glm::vec3(mid.x, lo.y - d, mid.z), false);
                add(glm::vec3(mid.x, mid.y, hi.z + d), false);
                add(glm::vec3(lo.x, lo.y, lo.z - d), false);
                // The farthest corner of the box at distance d (a node right at the accept limit).
                add(glm::vec3(hi.x - d, hi.y, hi.z), false);
            }
        }
        for (size_t i = 0; i < vs.samples.size(); i += 37)
            for (float d : {below, r, above}) {
                const glm::vec3 x = vs.samples[i].position;
                add(x + glm::vec3(d, 0, 0), false);
                add(x - glm::vec3(0, d, 0), false);
            }
        map.emitted = map.photons.size();
        const std::string what = "box faces r " + std::to_string(r);
        const Outcome out = compare(vs, map, splat_params(r, map), key_params(32, 32), what.c_str());
        report(what.c_str(), out);
        if (r == 2.0f) EXPECT_GT(counter(out.cone, "node_accepts"), 100.0);  // (r = 0.5 holds no whole leaf)
        SplatParams epanechnikov = splat_params(r, map);
        epanechnikov.kernel = Kernel::epanechnikov;
        compare(vs, map, epanechnikov, key_params(32, 32), (what + " epanechnikov").c_str());
    }
}

TEST(SplatClusterCone, GrazingPhotons) {
    std::mt19937 rng(23);
    SyntheticOptions o = cone_scene_options();
    o.axis_aligned = true;
    const ViewSamples vs = random_scene(o, rng);
    PhotonMap map = random_photons(vs, 2000, 0.3f, rng);
    for (size_t i = 0; i < map.photons.size(); ++i) {
        // ωi within a hair of the tangent plane of a sample's normal, on either side.
        Photon& p = map.photons[i];
        const glm::vec3 n = vs.samples[(i * 7919) % vs.samples.size()].normal;
        const glm::vec3 tangent = glm::normalize(glm::cross(n, random_unit(rng)));
        const float lift = (i % 3 == 0 ? 1e-7f : i % 3 == 1 ? 1e-5f : 2e-4f) * (i % 2 ? 1.0f : -1.0f);
        p.wi = glm::normalize(tangent + lift * n);
        p.normal = n;
    }
    for (float radius : {0.3f, 3.0f}) compare(vs, map, splat_params(radius, map), key_params(48, 40), "grazing");
}

TEST(SplatClusterCone, SingleSampleLeavesAndSamplesThroughMirrors) {
    std::mt19937 rng(5);
    SyntheticOptions o = sized(96, 64, cone_scene_options());
    o.coverage = 0.02;
    const ViewSamples sparse = random_scene(o, rng);
    const ClusterHierarchy h = build_with_cones(sparse, key_params(96, 64));
    size_t single = 0;
    for (uint32_t leaf : h.leaves) single += h.nodes[leaf].sample_end - h.nodes[leaf].sample_begin == 1 ? 1 : 0;
    EXPECT_GT(single, h.leaves.size() / 2);
    const PhotonMap map = random_photons(sparse, 1000, 1.0f, rng);
    for (float radius : {0.5f, 4.0f}) compare(sparse, map, splat_params(radius, map), key_params(96, 64), "sparse");
    SyntheticOptions m = cone_scene_options();
    m.specular_fraction = 0.6;
    const ViewSamples mirrored = random_scene(m, rng);
    const PhotonMap map2 = random_photons(mirrored, 2000, 0.5f, rng);
    compare(mirrored, map2, splat_params(0.8f, map2), key_params(48, 40), "mirrors");
}

// (Zero photons and zero samples, for every method: AnyMethod.ZeroPhotonsGiveZeroRadianceAndZeroSamplesNoOutput.)
TEST(SplatClusterCone, RefusesAHierarchyWithoutCones) {
    std::mt19937 rng(3);
    const ViewSamples vs = random_scene(cone_scene_options(), rng);
    const PhotonMap map = random_photons(vs, 100, 0.1f, rng);
    RenderControl control;
    Stats stats;
    const ClusterHierarchy plain = build_cluster_hierarchy(vs, key_params(48, 40));
    EXPECT_THROW(splat_cluster_cone(plain, vs, map, splat_params(0.3f, map), control, stats), InvalidInput);
}

// Bounded memory: a tiny pair cap makes many batches; accepts must still land once each, in photon order.
TEST(SplatClusterCone, TinyPairCapManyBatchesAndThreadCountsGiveTheSameOutput) {
    std::mt19937 rng(89);
    const SyntheticOptions o = sized(64, 48, cone_scene_options());
    const ViewSamples vs = random_scene(o, rng);
    const PhotonMap map = random_photons(vs, 1500, 0.5f, rng);
    const ClusterHierarchy h = build_with_cones(vs, key_params(64, 48));
    for (uint64_t cap : {uint64_t(1), uint64_t(500), uint64_t(8 * h.leaves.size())}) {
        SplatParams params = splat_params(cap == 1 ? 3.0f : 0.8f, map);
        params.max_pairs_in_memory = cap;
        auto run = [&](int threads, Stats& stats) {
            std::vector<glm::vec3> out;
            RenderControl control;
            tbb::task_arena(threads).execute([&] { out = splat_cluster_cone(h, vs, map, params, control, stats); });
            return out;
        };
        Stats one, two, brute, whole;
        const std::vector<glm::vec3> a = run(1, one), b = run(2, two);
        EXPECT_TRUE(a == b) << "cap " << cap << ": not bit-identical across thread counts";
        SplatParams uncapped = params;
        uncapped.max_pairs_in_memory = kDefaultMaxPairsInMemory;
        RenderControl control;
        const std::vector<glm::vec3> c = splat_cluster_cone(h, vs, map, uncapped, control, whole);
        EXPECT_TRUE(a == c) << "cap " << cap << ": depends on where batches end";
        expect_close(a, splat_brute(vs, map, params, control, brute), "tiny cap");
        EXPECT_GT(counter(one, "splat_batches"), cap < 1000 ? 10.0 : 1.0) << "cap " << cap;
        EXPECT_GT(counter(one, "node_accepts"), 0.0);
        EXPECT_EQ(counter(one, "contributing_pairs"), counter(brute, "contributing_pairs"));
        EXPECT_EQ(counter(two, "node_accepts"), counter(one, "node_accepts"));
        // Pair buffers and lists: 16 bytes per pair of the cap (with slack), plus the per-node list offsets;
        // one photon alone may go past a tiny cap by its own entries (at most one per leaf).
        const double bound = 16.0 * double(std::max<uint64_t>(cap, 4 * h.leaves.size())) +
                             double(sizeof(size_t) * (h.nodes.size() + 2));
        EXPECT_LE(one.bytes.at("leaf_photon_lists"), bound) << "cap " << cap;
        EXPECT_LE(two.bytes.at("leaf_photon_lists"), bound) << "cap " << cap;
    }
}

// ---- the Cornell box through the real pipeline ---------------------------------------------------------

TEST(SplatClusterCone, MatchesBruteOnTheCornellBox) {
    Scene scene;
    test::build_cornell_box(scene, true);  // glass and mirror spheres: samples behind glass, caustics
    const Camera camera = test::cornell_camera(40, 40);
    RenderControl control;
    Stats stats;
    ViewSampleSettings view_settings;
    view_settings.seed = 3;
    const ViewSamples samples = generate_view_samples(scene, camera, view_settings, control, stats);
    PhotonSettings photon_settings;
    photon_settings.count = 10000;
    photon_settings.seed = 3;
    const PhotonMap photons = trace_photons(scene, photon_settings, control, stats);
    size_t behind_glass = 0;
    for (const ViewSample& s : samples.samples) behind_glass += s.flags & kViaSpecular ? 1 : 0;
    EXPECT_GT(behind_glass, 20u);
    ClusterBuildOptions options;
    options.normal_cones = true;
    const ClusterHierarchy h = build_cluster_hierarchy(samples, ClusterKeyParams::from_camera(camera), options);
    const float r0 = default_radius(scene, photon_settings.count);
    for (float radius : {r0, 4.0f * r0}) {
        for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
            SplatParams params;
            params.radius = radius;
            params.emitted = std::max<uint64_t>(photons.emitted, 1);
            params.cos_normal_tolerance = 0.5f;
            params.kernel = kernel;
            Stats brute_stats, cone_stats;
            const std::vector<glm::vec3> expected = splat_brute(samples, photons, params, control, brute_stats);
            const std::vector<glm::vec3> actual = splat_cluster_cone(h, samples, photons, params, control, cone_stats);
            expect_close(actual, expected, "cornell");
            EXPECT_EQ(counter(cone_stats, "contributing_pairs"), counter(brute_stats, "contributing_pairs"));
            EXPECT_GT(counter(cone_stats, "node_accepts"), 0.0);
            std::printf("cornell r %.3f %s: accepts %.0f (%.0f samples of %.0f contributing), sample tests %.0f\n",
                        radius, to_string(kernel), counter(cone_stats, "node_accepts"),
                        counter(cone_stats, "accepted_samples"), counter(cone_stats, "contributing_pairs"),
                        counter(cone_stats, "photon_sample_tests"));
        }
    }
}

TEST(SplatClusterCone, RenderIsBitIdenticalForAnyThreadCount) {
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
    auto render_with = [&](int threads) {
        RenderSettings settings;
        settings.photons = 4000;
        settings.radius = 0.3f;  // large: many accepts
        settings.method = SplatMethod::cluster_cone;
        settings.threads = threads;
        settings.seed = 5;
        RenderControl control;
        return render(cornell_scene(), cornell_camera(32, 32), settings, control);
    };
    const RenderResult one = render_with(1);
    EXPECT_GT(one.stats.counters.at("node_accepts"), 100.0);
    for (int threads : {2, 8}) EXPECT_EQ(one.rgba(), render_with(threads).rgba()) << threads << " threads";
}

}  // namespace
}  // namespace ps
