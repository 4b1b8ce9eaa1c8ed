// The hard cases, each rendered with EVERY splat method: the output is finite, the exact methods
// equal `brute` (relative 1e-4 per component, plus 1e-6 of the image's largest value for summation order), the
// approximate `directional` is within 10 % of brute's total indirect light, and where an analytic value exists
// the image is compared with it. Inputs the core refuses must raise InvalidInput naming the cause.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <tuple>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/reference.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"
#include "test_support.h"

namespace {

using namespace ps;

constexpr float kPi = 3.14159265358979f;

std::vector<SplatMethod> all_methods() {
    std::vector<SplatMethod> methods;
    for (const std::string& name : splat_method_names()) methods.push_back(splat_method_from_string(name));
    return methods;
}

RenderResult render_with(const Scene& scene, const Camera& camera, RenderSettings settings, SplatMethod method) {
    settings.method = method;
    RenderControl control;
    return render(scene, camera, settings, control);
}

bool all_finite(const std::vector<float>& values) {
    return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

double total(const std::vector<float>& values) {
    double sum = 0.0;
    for (float v : values) sum += v;
    return sum;
}

// Renders with every method; checks finiteness and agreement with brute; returns the results by method.
std::map<SplatMethod, RenderResult> render_every_method(const Scene& scene, const Camera& camera,
                                                        const RenderSettings& settings, const std::string& label,
                                                        double directional_tolerance = 0.1) {
    std::map<SplatMethod, RenderResult> results;
    for (SplatMethod method : all_methods()) results[method] = render_with(scene, camera, settings, method);
    const RenderResult& brute = results.at(SplatMethod::brute);
    const float largest = brute.film[ps::FilmOutput::indirect].empty() ? 0.0f : *std::max_element(brute.film[ps::FilmOutput::indirect].begin(), brute.film[ps::FilmOutput::indirect].end());
    for (const auto& [method, r] : results) {
        SCOPED_TRACE(label + ", method " + to_string(method));
        EXPECT_TRUE(all_finite(r.rgba()));
        EXPECT_TRUE(all_finite(r.film[ps::FilmOutput::indirect]));
        EXPECT_EQ(r.film[ps::FilmOutput::indirect].size(), brute.film[ps::FilmOutput::indirect].size());
        if (r.film[ps::FilmOutput::indirect].size() != brute.film[ps::FilmOutput::indirect].size()) continue;
        if (method == SplatMethod::directional) {
            EXPECT_NEAR(total(r.film[ps::FilmOutput::indirect]), total(brute.film[ps::FilmOutput::indirect]), directional_tolerance * total(brute.film[ps::FilmOutput::indirect]) + 1e-9);
            continue;
        }
        size_t bad = 0;
        for (size_t i = 0; i < r.film[ps::FilmOutput::indirect].size(); ++i) {
            const float b = brute.film[ps::FilmOutput::indirect][i], m = r.film[ps::FilmOutput::indirect][i];
            if (!(std::fabs(b - m) <= 1e-4f * std::fabs(b) + 1e-6f * largest)) ++bad;
        }
        EXPECT_EQ(bad, 0u) << "components differing from brute";
    }
    return results;
}

// ---------------------------------------------------------------------------------------------------------------
// Grazing light and grazing view samples: a point light 1 cm above a 20 m plane, seen from 2 cm above it. Direct
// light must match ρ/π · I · cos θ / d² (θ near 90°) and every method brute.
TEST(HardCases, GrazingLightAndSamplesMatchTheAnalyticDirectLight) {
    Scene scene;
    const float albedo = 0.8f;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(albedo), 1.45f, glm::vec3(0.0f)});
    test::add_quad(scene, "plane", {-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}, white);
    test::add_quad(scene, "wall", {-10, 10, 0}, {10, 10, 0}, {10, 10, 3}, {-10, 10, 3}, white);
    const glm::vec3 lamp(0.0f, 2.0f, 0.01f);
    scene.add_light(test::point_light("lamp", lamp, 100.0f));
    const Camera camera = test::look_at({0, -2, 0.02f}, {0, 6, 0.0f}, 32, 32, 30.0f, {0, 0, 1}, 0.01f);
    RenderSettings settings;
    settings.photons = 20000;
    settings.radius = 0.1f;
    settings.direct_samples = 1;
    const auto results = render_every_method(scene, camera, settings, "grazing");
    RenderControl control;
    Stats stats;
    const ViewSamples samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    const RenderResult& r = results.at(SplatMethod::brute);
    double worst = 0.0;
    int checked = 0;
    for (const ViewSample& s : samples.samples) {
        const glm::vec3 x = s.position + samples.origin;
        if (std::fabs(x.z) > 1e-4f || std::fabs(x.y) > 9.0f) continue;  // the plane only
        const glm::vec3 to_light = lamp - x;
        const float d2 = glm::dot(to_light, to_light);
        const double expected = albedo / kPi * (100.0 / (4.0 * kPi)) * (to_light.z / std::sqrt(d2)) / d2;
        const double got = r.film[ps::FilmOutput::direct][3 * s.pixel + 1];
        worst = std::max(worst, std::fabs(got - expected) / expected);
        ++checked;
    }
    ASSERT_GT(checked, 50);
    EXPECT_LT(worst, 0.01) << "direct light at grazing incidence vs I·cosθ/d²·ρ/π";
}

// ---------------------------------------------------------------------------------------------------------------
// A closed room split in two by a 1 mm thick wall, the lamp in the left half. The wall's right (dark) face gets
// no light at all: direct light is shadowed, and no photon may be splatted across the wall. Near the base, photons
// on the lit floor that came off the wall's lit face point towards +x (they pass the facing test of the dark
// face); only the normal tolerance τ stops them. Turning it off (τ = 180°) must light the dark face.
struct ThinWall {
    Scene scene;
    Camera camera = test::look_at({0.6f, 0.0f, 0.25f}, {0.0f, 0.0f, 0.05f}, 32, 32, 50.0f);
    ThinWall() {
        const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
        test::add_box(scene, "room", {-1, -1, 0}, {1, 1, 2}, white);
        // The divider pierces the room's faces so that no ray can slip through a crack at its edges.
        test::add_box(scene, "wall", {-0.0005f, -1.01f, -0.01f}, {0.0005f, 1.01f, 2.01f}, white);
        scene.add_light(test::point_light("lamp", {-0.5f, 0.0f, 1.0f}, 100.0f));
    }
    // Largest indirect and direct radiance over the pixels that see the wall's dark face.
    std::pair<float, float> dark_face(const RenderResult& r) const {
        RenderControl control;
        Stats stats;
        const ViewSamples samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
        float indirect = 0.0f, direct = 0.0f;
        int seen = 0;
        for (const ViewSample& s : samples.samples) {
            if (!(s.normal.x > 0.99f) || std::fabs(s.position.x + samples.origin.x - 0.0005f) > 1e-4f) continue;
            ++seen;
            for (int c = 0; c < 3; ++c) {
                indirect = std::max(indirect, r.film[ps::FilmOutput::indirect][3 * s.pixel + c]);
                direct = std::max(direct, r.film[ps::FilmOutput::direct][3 * s.pixel + c]);
            }
        }
        EXPECT_GT(seen, 200) << "the camera must see the dark face";
        return {indirect, direct};
    }
};

TEST(HardCases, OneMillimetreWallLetsNoLightThroughAndEachLeakTestMatters) {
    const ThinWall wall;
    RenderSettings settings;
    settings.photons = 40000;
    settings.radius = 0.05f;  // 50× the wall's thickness
    for (SplatMethod method : all_methods()) {
        SCOPED_TRACE(to_string(method));
        const RenderResult tight = render_with(wall.scene, wall.camera, settings, method);
        EXPECT_GT(total(tight.film[ps::FilmOutput::indirect]), 0.0) << "the floor in view near the wall is lit: the test is not vacuous";
        const auto [indirect, direct] = wall.dark_face(tight);
        EXPECT_EQ(direct, 0.0f) << "direct light through the wall";
        EXPECT_EQ(indirect, 0.0f) << "photon light leaked through the wall";
        RenderSettings no_normal_test = settings;
        no_normal_test.normal_tolerance = 180.0f;  // n_x·n_p > −1: the normal test is off
        const RenderResult leaky = render_with(wall.scene, wall.camera, no_normal_test, method);
        EXPECT_GT(wall.dark_face(leaky).first, 0.0f) << "without the normal test the dark face must get leaked light";
    }
}

// A flat box whose 1 mm lid, floor and sides enclose a 1 mm tall cavity; lit from outside through a ceiling that
// sends photons onto the lid. The camera sits inside the cavity (the camera-inside-geometry case) and looks down
// at its floor, which is 2 mm below the lit lid top and faces the same way: distance, facing and normal tests all
// pass, only the plane-distance test |n·(x − p)| < κ r (κ r = 1 mm) keeps the lid's photons off it.
TEST(HardCases, StackedSurfacesOneMillimetreApartNeedThePlaneDistanceTest) {
    Scene scene;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    test::add_box(scene, "slab", {-0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 0.003f}, white);
    test::add_box(scene, "cavity", {-0.499f, -0.499f, 0.001f}, {0.499f, 0.499f, 0.002f}, white);
    test::add_quad(scene, "ceiling", {-3, -3, 1}, {-3, 3, 1}, {3, 3, 1}, {3, -3, 1}, white);
    scene.add_light(test::point_light("lamp", {0.0f, 0.0f, 0.5f}, 100.0f));
    const Camera camera = test::look_at({0.0f, 0.0f, 0.0019f}, {0.0f, 0.0002f, 0.001f}, 16, 16, 60.0f, {0, 1, 0}, 1e-5f);
    RenderSettings settings;
    settings.photons = 20000;
    settings.radius = 0.05f;
    settings.plane_distance = 0.02f;  // κ r = 1 mm
    for (SplatMethod method : all_methods()) {
        SCOPED_TRACE(to_string(method));
        const RenderResult inside = render_with(scene, camera, settings, method);
        EXPECT_GT(inside.stats.counters.at("view_samples"), 200.0) << "the camera sees the cavity floor";
        EXPECT_GT(inside.stats.counters.at("photons_stored"), 1000.0) << "the lid is lit: the test is not vacuous";
        EXPECT_EQ(*std::max_element(inside.rgba().begin(), inside.rgba().end() - 1), 1.0f) << "alpha only";
        for (size_t i = 0; i < inside.film[ps::FilmOutput::indirect].size(); ++i) ASSERT_EQ(inside.film[ps::FilmOutput::indirect][i], 0.0f) << "leak at " << i;
        RenderSettings no_plane_test = settings;
        no_plane_test.plane_distance = 0.0f;
        const RenderResult leaky = render_with(scene, camera, no_plane_test, method);
        EXPECT_GT(total(leaky.film[ps::FilmOutput::indirect]), 0.0) << "without the plane-distance test the lid's light must leak in";
    }
}

// ---------------------------------------------------------------------------------------------------------------
// 90° corners with an analytic answer: inside a closed box whose walls emit Le and reflect a, radiance is
// Le/(1 − a) everywhere. The camera looks into a corner. Density estimation near a corner sees part of its disc
// off the surface, which biases the indirect light low within r of the edges (a known property of photon
// splatting, measured here: < 5 % of the total at r = 0.05).
TEST(HardCases, CornerOfAClosedEmissiveBoxStaysNearTheAnalyticRadiance) {
    Scene scene;
    const float albedo = 0.5f, le = 1.0f;
    scene.add_material({"wall", MaterialKind::diffuse, glm::vec3(albedo), 1.45f, glm::vec3(le)});
    test::add_box(scene, "box", {-1, -1, -1}, {1, 1, 1}, 0);
    const auto results = render_every_method(scene, test::look_at({0.5f, 0.5f, 0.5f}, {1, 1, 1}, 16, 16, 40.0f),
                                             test::emissive_box_settings(100000, 0.05f, 32, 8), "corner");
    for (const auto& [method, r] : results) {
        double mean = 0.0;
        for (size_t p = 0; p < 16 * 16; ++p) mean += r.rgba()[4 * p + 1];
        mean /= 16 * 16;
        EXPECT_NEAR(mean, le / (1.0f - albedo), 0.05 * le / (1.0f - albedo)) << to_string(method);
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Scale and translation: the same Cornell box (with a glass block: refraction and total internal reflection)
// at scales 1e-3 and 1e4 (radius, lamp power and near clip scaled along), and at scale 1 moved by 1e3 and 1e5,
// against scale 1 at the origin, for every method. Photon paths are chaotic: a rounding difference at one bounce
// sends a photon elsewhere, so the indirect light differs pixel by pixel at the level of its noise (measured
// 12 % mean absolute at 10k photons for 1e-3 and 1e3) and its total by the noise of a total over diverged paths
// (about 0.5 % at 40k photons; measured up to 3.1 % at 10k). Checked: direct light to 1 % (mean absolute
// difference over the mean), the total indirect light to 3 % (6 σ), and at 1e4 the whole image to 1 %. That
// last bound is one of pixel noise, which the boundary correction raises near edges (it multiplies a pixel's
// photon noise by up to 4): it holds with the correction off (measured 0.86 %; on: 1.03 %). The correction's
// own scale invariance is KernelCoverage.TheSameAtEveryScale (identical coverage at 1e4).
struct ImageDifference {
    double direct = 0.0, indirect_total = 0.0, image = 0.0;
};

double mean_abs_relative(const std::vector<float>& a, const std::vector<float>& b) {
    double diff = 0.0, sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        diff += std::fabs(double(a[i]) - b[i]);
        sum += std::fabs(double(a[i]));
    }
    return sum > 0.0 ? diff / sum : diff;
}

ImageDifference compare(const RenderResult& a, const RenderResult& b) {
    ImageDifference d;
    d.direct = mean_abs_relative(a.film[ps::FilmOutput::direct], b.film[ps::FilmOutput::direct]);
    d.indirect_total = std::fabs(total(a.film[ps::FilmOutput::indirect]) - total(b.film[ps::FilmOutput::indirect])) / total(a.film[ps::FilmOutput::indirect]);
    d.image = mean_abs_relative(a.rgba(), b.rgba());
    return d;
}

double relative_image_difference(const RenderResult& a, const RenderResult& b) { return mean_abs_relative(a.rgba(), b.rgba()); }

RenderResult render_transformed(float scale, glm::vec3 offset, SplatMethod method, bool boundary_correction = true) {
    Scene scene;
    test::build_transformed_cornell_box(scene, scale, offset);
    RenderSettings settings;
    settings.photons = 40000;
    settings.radius = 0.1f * scale;
    settings.seed = 3;
    settings.boundary_correction = boundary_correction;
    return render_with(scene, test::transformed_cornell_camera(scale, offset, 24, 24), settings, method);
}

TEST(HardCases, SameImageAtScales1em3And1e4) {
    for (SplatMethod method : all_methods()) {
        SCOPED_TRACE(to_string(method));
        const RenderResult unit = render_transformed(1.0f, glm::vec3(0.0f), method);
        const ImageDifference small = compare(unit, render_transformed(1e-3f, glm::vec3(0.0f), method));
        const ImageDifference large = compare(unit, render_transformed(1e4f, glm::vec3(0.0f), method));
        for (const auto& [label, d] : {std::pair<const char*, ImageDifference>{"scale 1e-3", small},
                                       {"scale 1e4", large}}) {
            EXPECT_LT(d.direct, 1e-2) << label;
            EXPECT_LT(d.indirect_total, 3e-2) << label;
        }
        const auto plain = [&](float scale) { return render_transformed(scale, glm::vec3(0.0f), method, false); };
        EXPECT_LT(compare(plain(1.0f), plain(1e4f)).image, 1e-2);
    }
}

// A scene far from the world origin renders as at the origin (issue 6: "translated by 1e5 giving the same image
// to 1e-3"), given the way Blender gives it: meshes in object space, the object transforms carrying the offset,
// lamp and camera positions in double (see scene.h, render space). Offsets 1e3 and 1e5, on the render origin's
// grid (the render-space scene is then bit for bit the one at the origin) and off it by float32 fractions
// (what a Blender location holds: the render-space scene then rounds differently, so ties break otherwise and
// photon paths may diverge). Measured (40k photons, 24×24, every method): on the grid the image is identical;
// off it, direct 2.0e-7 and indirect total 6.0e-5, at 1e3 and at 1e5 alike. The box's scene differs from the one
// above in two ties only: its glass block stands 1 cm above the floor instead of sharing its bottom face with
// it, and the camera is moved off the box's symmetry plane, where pixel centres fell exactly on the box's edges.
// In such ties any rounding decides which face a ray hits: the scene above moved by just 0.3 (no precision
// problem at all) already differs by 0.8 % (direct) and 1.2 % (indirect total).
// The moved box (offset in its transforms, or in its vertices) rendered at 24×24 with 40k photons.
RenderResult render_moved_box(SplatMethod method, const glm::dvec3& offset, bool offset_in_vertices = false) {
    RenderSettings settings;
    settings.photons = 40000;
    settings.radius = 0.1f;
    settings.seed = 3;
    Scene scene;
    test::build_moved_cornell_box(scene, offset, offset_in_vertices);
    return render_with(scene, test::moved_cornell_camera(offset, 24, 24), settings, method);
}

TEST(HardCases, SameImageMovedBy1e3And1e5) {
    for (SplatMethod method : all_methods()) {
        SCOPED_TRACE(to_string(method));
        const auto render_moved = [&](const glm::dvec3& offset) { return render_moved_box(method, offset); };
        const RenderResult origin = render_moved(glm::dvec3(0.0));
        for (double d : {1e3, 1e5}) {
            for (double fraction : {0.0, double(float(d + 0.3)) - d}) {
                const glm::dvec3 offset(d + fraction, -d - fraction, d + 0.5 * fraction);
                const ImageDifference diff = compare(origin, render_moved(offset));
                std::printf("%s moved by %.7g: direct %.3g, indirect total %.3g, image %.3g\n", to_string(method),
                            offset.x, diff.direct, diff.indirect_total, diff.image);
                EXPECT_LT(diff.direct, 1e-3) << "moved by " << offset.x;
                EXPECT_LT(diff.indirect_total, 1e-2) << "moved by " << offset.x;
                if (fraction == 0.0) EXPECT_EQ(diff.image, 0.0) << "moved by " << offset.x;
            }
        }
    }
}

// The other ways in, moved by an off-grid 1e5: progressive passes (ProgressiveRender keeps its camera) and the
// reference renderer, each against the same at the origin; and where the render origin goes (scene.h).
TEST(HardCases, ProgressiveAndReferenceRenderMovedScenesAlikeAndTheOriginFollowsTheGeometry) {
    const double d = 1e5, fraction = double(float(d + 0.3)) - d;
    const glm::dvec3 far(d + fraction, -d - fraction, d + 0.5 * fraction);
    Scene at_origin, moved;
    test::build_moved_cornell_box(at_origin, glm::dvec3(0.0));
    test::build_moved_cornell_box(moved, far);
    EXPECT_EQ(at_origin.origin(), glm::dvec3(0.0));                  // its box holds the world origin
    EXPECT_EQ(moved.origin(), glm::dvec3(1e5, -1e5, 1e5));          // the box's centre on a 4 m grid
    EXPECT_LT(glm::length(glm::vec3(moved.lights()[0].position) - glm::vec3(0.3f, -0.3f, 1.95f)), 0.01f);

    RenderSettings settings;
    settings.photons = 10000;
    settings.radius = 0.1f;
    settings.iterations = 2;
    RenderControl control;
    const RenderResult a = render(at_origin, test::moved_cornell_camera(glm::dvec3(0.0), 16, 16), settings, control);
    const RenderResult b = render(moved, test::moved_cornell_camera(far, 16, 16), settings, control);
    EXPECT_LT(mean_abs_relative(a.film[ps::FilmOutput::direct], b.film[ps::FilmOutput::direct]), 1e-3);
    EXPECT_LT(mean_abs_relative(a.rgba(), b.rgba()), 1e-2);

    ReferenceSettings reference;
    reference.samples = 2;
    reference.caustic_photons = 2000;
    const ReferenceResult ra = render_reference(at_origin, test::moved_cornell_camera(glm::dvec3(0.0), 16, 16), reference, control);
    const ReferenceResult rb = render_reference(moved, test::moved_cornell_camera(far, 16, 16), reference, control);
    EXPECT_LT(mean_abs_relative(ra.rgba, rb.rgba), 1e-2);

    // Moving an instance keeps the origin (no O(scene) work per move); fit_origin then follows the instances.
    moved.set_instance_transform(0, glm::dmat4(1.0));
    EXPECT_EQ(moved.origin(), glm::dvec3(1e5, -1e5, 1e5));
}

// The viewport's way (scene_cache.py): a scene built at the origin, every instance moved by 1e5 in place with
// set_instance_transform, then fit_origin: bit for bit the image of the scene built there, for every method.
// Embree traces a ray through an instance in the mesh's own space and asserts (aborting the process, Blender with
// it) once a coordinate there passes 1.8e18. The fuzzer found a transform whose axes are nearly parallel (its
// columns below); a mesh scaled down past 1e9 does the same. Such instances cover nothing and are counted as
// dropped. And a camera absurdly far from a mesh scaled down a millionfold (1e13 × 1e6 = 1e19 in the mesh's
// space) still renders: rays from that far start where they enter the scene's box.
TEST(HardCases, InstancesEmbreeCannotTraceAreDroppedAndFarRaysStartAtTheScene) {
    glm::dmat4 nearly_parallel(1.0);
    nearly_parallel[0] = glm::dvec4(3.0, 3.0, 2.97813, 0.0);
    nearly_parallel[1] = glm::dvec4(2.6, 2.6, 2.6, 0.0);
    nearly_parallel[2] = glm::dvec4(-0.2, -0.2, -0.2, 0.0);
    glm::dmat4 tiny(1e-10);
    tiny[3] = glm::dvec4(0.0, 0.0, 0.5, 1.0);
    for (const glm::dmat4& bad : {nearly_parallel, tiny}) {
        Scene scene;
        test::build_cornell_box(scene, false);
        const size_t before = scene.dropped_triangles();
        test::add_box(scene, "bad", {-0.2f, -0.2f, 0.2f}, {0.2f, 0.2f, 0.6f}, 0, bad);
        EXPECT_EQ(scene.dropped_triangles(), before + 12);
        RenderSettings settings;
        settings.photons = 2000;
        render_every_method(scene, test::cornell_camera(8, 8), settings, "ill-conditioned instance");
    }
    Scene scene;
    scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    glm::dmat4 micro(1e-6);
    micro[3] = glm::dvec4(0.0, 0.0, 0.0, 1.0);
    test::add_box(scene, "micro", {-0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 1.0f}, 0, micro);
    scene.add_light(test::point_light("lamp", {0.0f, -2e-6f, 2e-6f}, 1e-10f));
    const Camera far = test::look_at({0.0f, -1e13f, 5e-7f}, {0.0f, 0.0f, 5e-7f}, 1, 1, 1e-3f, {0, 0, 1}, 1e10f);
    RenderSettings settings;
    settings.photons = 1000;
    settings.radius = 1e-7f;
    settings.transparent = true;  // alpha says whether the camera ray hit the box
    for (SplatMethod method : all_methods()) {
        const RenderResult r = render_with(scene, far, settings, method);
        EXPECT_TRUE(all_finite(r.rgba())) << to_string(method);
        EXPECT_EQ(r.rgba()[3], 1.0f) << to_string(method);
    }
}

TEST(HardCases, InstancesMovedFarInPlaceRenderAsAFreshSceneAfterFitOrigin) {
    const double d = 1e5, fraction = double(float(d + 0.3)) - d;
    const glm::dvec3 far(d + fraction, -d - fraction, d + 0.5 * fraction);
    glm::dmat4 moved_transform(1.0);
    moved_transform[3] = glm::dvec4(far, 1.0);
    Scene in_place, fresh;
    test::build_moved_cornell_box(in_place, glm::dvec3(0.0));
    test::build_moved_cornell_box(fresh, far);
    const Camera camera = test::moved_cornell_camera(far, 16, 16);
    RenderSettings settings;
    settings.photons = 5000;
    settings.radius = 0.1f;
    render_with(in_place, camera, settings, SplatMethod::brute);  // builds the BVH: the moves below refit it
    for (uint32_t i = 0; i < in_place.instances().size(); ++i) in_place.set_instance_transform(i, moved_transform);
    in_place.clear_lights();
    in_place.add_light(test::point_light("lamp", {}, 100.0f), far + glm::dvec3(0.0, 0.0, 1.8f));
    EXPECT_EQ(in_place.origin(), glm::dvec3(0.0));
    in_place.fit_origin();
    EXPECT_EQ(in_place.origin(), fresh.origin());
    for (SplatMethod method : all_methods()) {
        const RenderResult a = render_with(in_place, camera, settings, method), b = render_with(fresh, camera, settings, method);
        EXPECT_EQ(a.rgba(), b.rgba()) << to_string(method);
    }
}

// The same box with the offset in its *vertices* (identity transforms: float32 input, rounded to 7.8 mm steps at
// 1e5, as a mesh with applied transforms or imported survey data gives it). The scene keeps such a mesh relative
// to its box's centre (MeshData::centre), so it renders as the rounded geometry it is. Measured (40k photons,
// every method): 1e3: direct 4.7e-7, indirect total 0; 1e5: direct 3.5e-5, indirect total 6.7e-4 — what moving
// the box's vertices by up to 3.9 mm costs. Without the re-centring (offset_ray_origin's rounding_scale alone):
// 1.1e-4 / 8.7e-4 and 4.1 % / 3.1 %; before render space (the box with ties): 0.66 % / −3.1 % and 34 % / −75 %.
// Still not precise: geometry finer than float32's spacing where its vertices are (at 1e5, under 7.8 mm).
TEST(HardCases, SameImageWithVerticesMovedBy1e3And1e5) {
    for (SplatMethod method : all_methods()) {
        const auto render_moved = [&](const glm::dvec3& offset) { return render_moved_box(method, offset, true); };
        const RenderResult origin = render_moved(glm::dvec3(0.0));
        for (double d : {1e3, 1e5}) {
            const ImageDifference diff = compare(origin, render_moved(glm::dvec3(d, -d, d)));
            std::printf("%s vertices moved by %g: direct %.3g, indirect total %.3g\n", to_string(method), d, diff.direct,
                        diff.indirect_total);
            EXPECT_LT(diff.direct, 1e-3) << "moved by " << d;
            EXPECT_LT(diff.indirect_total, 1e-2) << "moved by " << d;
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Bad triangles: zero-area, repeated-vertex and overflowing ones are dropped and counted in the stats; NaN or
// infinite vertices are refused with an error naming the object; duplicated triangles render as the single ones.
TEST(HardCases, DegenerateTrianglesAreDroppedAndCountedAndNanIsRefusedNamingTheObject) {
    Scene scene;
    test::build_cornell_box(scene, false);
    const float v[] = {0, 0, 0.5f, 1, 0, 0.5f, 2, 0, 0.5f, 0, 1, 0.5f, 3e38f, 3e38f, 0.5f};
    const int32_t t[] = {0, 1, 2,   // collinear: zero area
                         0, 0, 3,   // repeated vertex
                         0, 4, 3};  // finite vertices, but the area overflows to infinity
    MeshInput mesh = test::mesh_input("Junk", v, 5, t, 3);
    scene.add_mesh(mesh);
    EXPECT_EQ(scene.dropped_triangles(), 3u);
    RenderSettings settings;
    settings.photons = 5000;
    const auto results = render_every_method(scene, test::cornell_camera(16, 16), settings, "degenerate");
    for (const auto& [method, r] : results) EXPECT_EQ(r.stats.counters.at("dropped_triangles"), 3.0);

    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        float w[15];
        std::copy(v, v + 15, w);
        w[4] = bad;
        mesh.vertices = w;
        try {
            scene.add_mesh(mesh);
            FAIL() << "a NaN/Inf vertex was accepted";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("Junk"), std::string::npos) << e.what();
        }
    }
}

TEST(HardCases, DuplicatedTrianglesRenderLikeSingleOnes) {
    Scene single, doubled;
    test::build_cornell_box(single, false);
    test::build_cornell_box(doubled, false);
    test::add_quad(doubled, "floor_again", {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, 0);
    RenderSettings settings;
    settings.photons = 5000;
    const auto a = render_every_method(single, test::cornell_camera(16, 16), settings, "single");
    const auto b = render_every_method(doubled, test::cornell_camera(16, 16), settings, "doubled");
    for (SplatMethod method : all_methods())
        EXPECT_LT(relative_image_difference(a.at(method), b.at(method)), 1e-2) << to_string(method);
}

// ---------------------------------------------------------------------------------------------------------------
// Nothing to light or nothing lit: the image is exactly the background / exactly black, for every method.
TEST(HardCases, EmptySceneNoLightsZeroPowerLightsAndALightShutInABox) {
    const Camera camera = test::cornell_camera(8, 8);
    RenderSettings settings;
    settings.photons = 2000;
    Scene empty;
    empty.set_background({0.1f, 0.2f, 0.3f});
    Scene unlit;
    unlit.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    test::add_quad(unlit, "floor", {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, 0);
    Scene zero_power;
    test::build_cornell_box(zero_power, false);
    Light off = test::point_light("off", {0, 0, 1}, 0.0f);
    // build_cornell_box adds a 100 W lamp: this scene keeps only zero-power lights.
    Scene dark;
    dark.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    test::add_box(dark, "room", {-1, -1, 0}, {1, 1, 2}, 0);
    dark.add_light(off);
    Light sun;
    sun.name = "zero_sun";
    sun.kind = LightKind::sun;
    sun.value = glm::vec3(0.0f);
    dark.add_light(sun);
    Scene shut;  // a lamp inside a closed box, the camera outside
    shut.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    test::add_box(shut, "crate", {-0.3f, -0.3f, 0.7f}, {0.3f, 0.3f, 1.3f}, 0);
    test::add_quad(shut, "floor", {-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}, 0);
    shut.add_light(test::point_light("caged", {0, 0, 1}, 1000.0f));
    // r below the 0.7 m between the crate's inside floor and the floor outside, which face the same way: with
    // the automatic radius at 2000 photons (1.3 m) those photons are splatted onto the floor outside (a leak only
    // the plane-distance test would stop; see the stacked-surfaces case).
    settings.radius = 0.1f;
    for (const auto& [name, scene, expected] :
         {std::tuple<const char*, const Scene*, glm::vec3>{"empty", &empty, {0.1f, 0.2f, 0.3f}},
          {"no lights", &unlit, glm::vec3(0.0f)},
          {"zero-power lights", &dark, glm::vec3(0.0f)},
          {"lamp in a closed box", &shut, glm::vec3(0.0f)}}) {
        for (SplatMethod method : all_methods()) {
            SCOPED_TRACE(std::string(name) + ", " + to_string(method));
            const RenderResult r = render_with(*scene, camera, settings, method);
            for (size_t p = 0; p < 64; ++p)
                for (int c = 0; c < 3; ++c) ASSERT_EQ(r.rgba()[4 * p + c], expected[c]) << "pixel " << p;
        }
    }
    // The crate's photons exist (the lamp is not simply off): they stay inside.
    RenderControl control;
    const RenderResult caged = render(shut, camera, settings, control);
    EXPECT_GT(caged.stats.counters.at("photons_stored"), 100.0);
}

// A camera inside a closed, unlit box sees black (not NaN, not garbage) with every method.
TEST(HardCases, CameraInsideClosedGeometry) {
    Scene scene;
    test::build_cornell_box(scene, false);
    test::add_box(scene, "closet", {-0.2f, -3.0f, 0.8f}, {0.2f, -2.6f, 1.2f}, 0);
    const Camera camera = test::look_at({0, -2.8f, 1}, {0, 0, 1}, 8, 8, 40.0f, {0, 0, 1}, 0.01f);
    RenderSettings settings;
    settings.photons = 5000;
    for (SplatMethod method : all_methods()) {
        const RenderResult r = render_with(scene, camera, settings, method);
        for (size_t p = 0; p < 64; ++p)
            for (int c = 0; c < 3; ++c) ASSERT_EQ(r.rgba()[4 * p + c], 0.0f) << to_string(method);
    }
}

TEST(HardCases, OrthographicCamera) {
    Scene scene;
    test::build_cornell_box(scene, true);
    glm::mat4 to_world(1.0f);
    to_world[1] = glm::vec4(0, 0, 1, 0);   // camera +y = world +z
    to_world[2] = glm::vec4(0, -1, 0, 0);  // camera looks down −z = world +y
    to_world[3] = glm::vec4(0, -3.9f, 1, 1);
    glm::mat4 ortho(1.0f);  // half extents 1.2 × 1.2, clip 0.1 .. 20
    ortho[0][0] = 1.0f / 1.2f;
    ortho[1][1] = 1.0f / 1.2f;
    ortho[2][2] = -2.0f / (20.0f - 0.1f);
    ortho[3][2] = -(20.0f + 0.1f) / (20.0f - 0.1f);
    const Camera camera(to_world, ortho, 24, 24);
    ASSERT_TRUE(camera.orthographic());
    RenderSettings settings;
    settings.photons = 20000;
    const auto results = render_every_method(scene, camera, settings, "orthographic");
    EXPECT_GT(total(results.at(SplatMethod::brute).film[ps::FilmOutput::indirect]), 0.0);
}

// ---------------------------------------------------------------------------------------------------------------
// Radius 0 (automatic), tiny and larger than the scene; photon count 0 and 1; resolution 1×1.
TEST(HardCases, ExtremeRadiiPhotonCountsAndResolution) {
    Scene scene;
    test::build_cornell_box(scene, true);
    struct Case {
        const char* name;
        float radius;
        uint64_t photons;
        int size;
    };
    for (const Case& c : {Case{"radius 0 (automatic)", 0.0f, 5000, 16}, Case{"radius 1e-9", 1e-9f, 5000, 16},
                          Case{"radius 1e3", 1e3f, 2000, 16}, Case{"0 photons", 0.1f, 0, 16},
                          Case{"1 photon", 0.1f, 1, 16}, Case{"1x1 pixel", 0.1f, 5000, 1}}) {
        RenderSettings settings;
        settings.radius = c.radius;
        settings.photons = c.photons;
        // Directional bins cannot apply the normal test photon by photon: with every photon reaching every sample
        // (r = 1e3) photons of walls facing elsewhere land in the bins too (measured: +106 % over brute).
        const auto results = render_every_method(scene, test::cornell_camera(c.size, c.size), settings, c.name,
                                                 c.radius > 10.0f ? 1.5 : 0.1);
        if (c.photons == 0)
            for (const auto& [method, r] : results) EXPECT_EQ(total(r.film[ps::FilmOutput::indirect]), 0.0) << c.name;
        if (c.radius == 1e3f) {
            // Every photon reaches every sample facing it: the estimate is tiny but finite and positive.
            EXPECT_GT(total(results.at(SplatMethod::brute).film[ps::FilmOutput::indirect]), 0.0);
        }
    }
}

// 8K (7680×4320) fits this machine's default budget, and is refused before allocating with a smaller one,
// naming the structure, the resolution to lower and the budget.
TEST(HardCases, EightKIsRefusedBeforeAllocatingWhenOverTheBudget) {
    const Camera camera = test::cornell_camera(7680, 4320);
    RenderSettings settings;
    settings.photons = 1000;
    settings.memory_budget = uint64_t(1) << 30;  // 1 GiB: 8K needs about 5 GiB
    RenderControl control;
    try {
        render(test::cornell_scene(), camera, settings, control);
        FAIL() << "8K fitted in 1 GiB";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(e.field(), "resolution");
        const std::string what = e.what();
        EXPECT_NE(what.find("view_samples"), std::string::npos) << what;
        EXPECT_NE(what.find("memory_budget"), std::string::npos) << what;
        EXPECT_NE(what.find("over"), std::string::npos) << what;
    }
    Stats stats;
    MemoryBudget budget(0, stats);
    settings.memory_budget = 0;
    if (default_memory_budget() > (uint64_t(12) << 30)) {
        EXPECT_NO_THROW(reserve_frame(budget, test::cornell_scene(), camera, settings)) << "8K fits the default budget here";
    }
}

TEST(HardCases, PhotonCountBeyondTheBudgetIsRefusedNamingPhotons) {
    Scene scene;
    test::build_cornell_box(scene, true);
    RenderSettings settings;
    settings.photons = 50'000'000;
    settings.memory_budget = uint64_t(256) << 20;
    RenderControl control;
    try {
        render(scene, test::cornell_camera(8, 8), settings, control);
        FAIL() << "50M photons fitted in 256 MiB";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(e.field(), "photons");
        EXPECT_NE(std::string(e.what()).find("photon_map"), std::string::npos) << e.what();
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Total internal reflection: a lamp inside a glass block traps most photons in TIR chains. With a path bound of
// 1000 every method ends (promptly) and agrees with brute.
TEST(HardCases, TotalInternalReflectionChainsEnd) {
    Scene scene;
    test::build_cornell_box(scene, false);
    const uint32_t glass = scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
    test::add_box(scene, "block", {-0.4f, -0.4f, 0.2f}, {0.4f, 0.4f, 1.0f}, glass);
    scene.add_light(test::point_light("inside", {0.0f, 0.0f, 0.6f}, 100.0f));
    RenderSettings settings;
    settings.photons = 5000;
    settings.max_bounces = 1000;
    settings.radius = 0.05f;
    const auto results = render_every_method(scene, test::cornell_camera(16, 16), settings, "TIR");
    EXPECT_GT(results.at(SplatMethod::brute).stats.counters.at("caustic_photons_stored"), 0.0);
}

// ---------------------------------------------------------------------------------------------------------------
// 10^5 photons at one point, on a view sample: every method splats them onto the samples within r, exactly
// ρ/π · ΣΦ / (π r² N) (the photons face the samples; uniform kernel).
TEST(HardCases, HundredThousandCoincidentPhotonsOnAViewSample) {
    Scene scene;
    const float albedo = 0.5f;
    scene.add_material({"white", MaterialKind::diffuse, glm::vec3(albedo), 1.45f, glm::vec3(0.0f)});
    test::add_quad(scene, "plane", {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, 0);
    const Camera camera = test::look_at({0, 0, 2}, {0, 0, 0}, 32, 32, 40.0f, {0, 1, 0});
    RenderControl control;
    Stats stats;
    const ViewSamples samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    const ViewSample& centre = samples.samples[samples.samples.size() / 2 + 16];
    PhotonMap photons;
    const glm::vec3 at = centre.position + samples.origin;
    photons.photons.assign(100000, Photon{at, glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), glm::vec3(2.0f), 0u});
    photons.emitted = 400000;
    SplatParams params;
    params.radius = 0.2f;  // about 4 pixels: a few dozen samples within r
    params.emitted = photons.emitted;
    const ClusterHierarchy plain = build_cluster_hierarchy(samples, ClusterKeyParams::from_camera(camera));
    ClusterBuildOptions with_cones;
    with_cones.normal_cones = true;
    const ClusterHierarchy coned = build_cluster_hierarchy(samples, ClusterKeyParams::from_camera(camera), with_cones);
    const float r = params.radius;
    const double expected = albedo / kPi * 2.0 * 100000.0 / (kPi * r * r * 400000.0);
    for (SplatMethod method : all_methods()) {
        Stats s;
        std::vector<glm::vec3> indirect;
        switch (method) {
            case SplatMethod::brute: indirect = splat_brute(samples, photons, params, control, s); break;
            case SplatMethod::tiled: indirect = splat_tiled(samples, camera, photons, params, control, s); break;
            case SplatMethod::gather: indirect = splat_gather(samples, photons, params, control, s); break;
            case SplatMethod::cluster: indirect = splat_cluster(plain, samples, photons, params, control, s); break;
            case SplatMethod::cluster_cone:
                indirect = splat_cluster_cone(coned, samples, photons, params, control, s);
                break;
            case SplatMethod::directional:
                indirect = splat_directional(plain, samples, photons, params, control, s);
                break;
        }
        int lit = 0;
        double worst = 0.0;
        for (size_t i = 0; i < samples.samples.size(); ++i) {
            const glm::vec3 d = samples.samples[i].position - centre.position;
            ASSERT_TRUE(std::isfinite(indirect[i].x)) << to_string(method);
            if (glm::dot(d, d) < 0.8f * r * r) {
                ++lit;
                worst = std::max(worst, std::fabs(indirect[i].y - expected) / expected);
            } else if (glm::dot(d, d) > 1.2f * r * r && method != SplatMethod::directional) {
                ASSERT_EQ(indirect[i].y, 0.0f) << to_string(method) << ": light beyond r";
            }
        }
        EXPECT_GT(lit, 4) << to_string(method);
        EXPECT_LT(worst, method == SplatMethod::directional ? 0.5 : 1e-4) << to_string(method);
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Determinism: the same seed gives a bit-identical image with 1, 2 and 8 threads, for every method.
TEST(HardCases, BitIdenticalImagesWithOneTwoAndEightThreadsForEveryMethod) {
    Scene scene;
    test::build_cornell_box(scene, true);
    RenderSettings settings;
    settings.photons = 5000;
    settings.seed = 11;
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);  // 8 threads even on 2 cores
    for (SplatMethod method : all_methods()) {
        settings.threads = 1;
        const RenderResult one = render_with(scene, test::cornell_camera(32, 32), settings, method);
        for (int threads : {2, 8}) {
            settings.threads = threads;
            const RenderResult many = render_with(scene, test::cornell_camera(32, 32), settings, method);
            ASSERT_EQ(one.rgba(), many.rgba()) << to_string(method) << " with " << threads << " threads";
        }
    }
}

}  // namespace

namespace {

using namespace ps;

// Found by fuzzing (fuzz/corpus/): a light at 3e38 made photon rays whose origin Embree's assertion refuses,
// aborting the process. Coordinates beyond ±1e15 are now refused (lights, camera) or dropped and counted
// (triangles), and the ray tracer ignores any ray Embree would assert on.
TEST(HardCases, CoordinatesBeyondWhatEmbreeAcceptsAreRefusedOrDropped) {
    Scene scene;
    test::build_cornell_box(scene, false);
    try {
        scene.add_light(test::point_light("far", {0.0f, 3e38f, 0.0f}, 100.0f));
        FAIL() << "a light at 3e38 was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(e.field(), "point light 'far'.position");
    }
    const size_t dropped = scene.dropped_triangles();
    test::add_quad(scene, "huge", {0, 0, 2e18f}, {1, 0, 2e18f}, {1, 1, 2e18f}, {0, 1, 2e18f}, 0);
    EXPECT_EQ(scene.dropped_triangles(), dropped + 2);
    EXPECT_THROW(test::look_at({0, 2e18f, 1}, {0, 0, 1}, 4, 4), InvalidInput);
    Hit hit;
    const Ray bad{{0.0f, 0.0f, 3e38f}, {0.0f, 0.0f, -1.0f}};
    EXPECT_FALSE(scene.ray_tracer().intersect(bad, 0.0f, INFINITY, hit));
    EXPECT_FALSE(scene.ray_tracer().occluded(bad, 0.0f, INFINITY));
    const Ray nan_ray{{0.0f, 0.0f, 1.0f}, {NAN, 0.0f, 0.0f}};
    EXPECT_FALSE(scene.ray_tracer().intersect(nan_ray, 0.0f, INFINITY, hit));
}

// Found by fuzzing: a background of 3e38 (finite, so accepted) overflowed the direct light to infinite pixels.
// Emitted values are now bounded by 1e10 (the sun's radiance is ~2e7), and a render whose pixels still leave the
// float range is refused instead of returned.
TEST(HardCases, EmissionBeyond1e10IsRefusedNamingTheField) {
    Scene scene;
    try {
        scene.set_background({0.0f, 7.5f, 3e38f});
        FAIL() << "a background of 3e38 was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(e.field(), "background");
    }
    EXPECT_THROW(scene.add_light(test::point_light("sunlike", {0, 0, 1}, 1e12f)), InvalidInput);
    EXPECT_THROW(scene.add_material({"hot", MaterialKind::diffuse, glm::vec3(0.5f), 1.45f, glm::vec3(2e10f)}),
                 InvalidInput);
    EXPECT_NO_THROW(scene.set_background(glm::vec3(1e10f)));
}

}  // namespace
