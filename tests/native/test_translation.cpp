// The scene model the add-on translates Blender into: instanced meshes (one BLAS, many transforms), textures
// looked up at UVs, spot and ellipse lights in Cycles' units, ray visibility and holdout, the far clip.
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "photonsplat/light_sources.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/shading.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"
#include "test_scenes.h"

namespace {

using namespace ps;
constexpr float kPi = 3.14159265358979323846f;

// A unit quad in the z = 0 plane, [-0.5, 0.5]², UVs (0..1) at its corners, one material.
uint32_t add_unit_quad(Scene& scene, uint32_t material) {
    const float v[12] = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    const int32_t m[2] = {static_cast<int32_t>(material), static_cast<int32_t>(material)};
    MeshInput mesh = test::mesh_input("quad", v, 4, t, 2, m);
    mesh.uvs = uv;
    return scene.add_mesh_data(mesh);
}

glm::mat4 translation(float x, float y, float z) { return glm::translate(glm::mat4(1.0f), glm::vec3(x, y, z)); }

Ray down_at(float x, float y) { return Ray{{x, y, 5.0f}, {0.0f, 0.0f, -1.0f}}; }

TEST(Instancing, ThousandInstancesStoreOneMeshAndHitsNameTheirInstance) {
    Scene scene;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    const uint32_t quad = add_unit_quad(scene, white);
    for (int i = 0; i < 1000; ++i) scene.add_instance(quad, translation(2.0f * (i % 40), 2.0f * (i / 40), 0.0f));
    EXPECT_EQ(scene.meshes().size(), 1u);
    EXPECT_EQ(scene.stored_triangle_count(), 2u);
    EXPECT_EQ(scene.triangle_count(), 2000u);
    // The BVH holds one mesh: its size grows by a transform per instance, not by the mesh's triangles.
    EXPECT_LT(scene.ray_tracer().bytes(), 1000u * 200u);

    const int k = 537;
    const float x = 2.0f * (k % 40) + 0.2f, y = 2.0f * (k / 40) - 0.1f;
    Hit hit;
    ASSERT_TRUE(scene.ray_tracer().intersect(down_at(x, y), 0.0f, 100.0f, hit));
    EXPECT_EQ(hit.instance, static_cast<uint32_t>(k));
    const SurfacePoint s = surface_at(scene, down_at(x, y), hit);
    EXPECT_NEAR(s.position.x, x, 1e-4f);
    EXPECT_NEAR(s.position.y, y, 1e-4f);
    EXPECT_NEAR(s.position.z, 0.0f, 1e-5f);
    EXPECT_NEAR(s.geometric_normal.z, 1.0f, 1e-5f);
    EXPECT_FALSE(scene.ray_tracer().intersect(down_at(1.0f, 1.0f), 0.0f, 100.0f, hit));  // between instances
}

TEST(Instancing, MovingAnInstanceUpdatesHitsWithoutRebuildingMeshes) {
    Scene scene;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    const uint32_t quad = add_unit_quad(scene, white);
    const uint32_t a = scene.add_instance(quad, translation(0, 0, 0));
    scene.add_instance(quad, translation(5, 0, 0));
    const RayTracer* before = &scene.ray_tracer();
    Hit hit;
    ASSERT_TRUE(before->intersect(down_at(0, 0), 0.0f, 100.0f, hit));

    // Rotated 90° about x and moved: it now stands upright at x = 10.
    glm::mat4 moved = glm::rotate(translation(10, 0, 0), kPi / 2.0f, glm::vec3(1, 0, 0));
    scene.set_instance_transform(a, moved);
    const RayTracer* after = &scene.ray_tracer();
    EXPECT_EQ(before, after);  // the same Embree scene, updated in place
    EXPECT_FALSE(after->intersect(down_at(0, 0), 0.0f, 100.0f, hit));
    const Ray sideways{{10.0f, -5.0f, 0.1f}, {0.0f, 1.0f, 0.0f}};
    ASSERT_TRUE(after->intersect(sideways, 0.0f, 100.0f, hit));
    EXPECT_EQ(hit.instance, a);
    const SurfacePoint s = surface_at(scene, sideways, hit);
    EXPECT_NEAR(std::fabs(s.geometric_normal.y), 1.0f, 1e-5f);  // the normal turned with the instance

    // Zero scale: the instance disappears, and comes back when scaled up again.
    scene.set_instance_transform(a, glm::scale(translation(10, 0, 0), glm::vec3(0.0f)));
    EXPECT_FALSE(scene.ray_tracer().intersect(sideways, 0.0f, 100.0f, hit));
    EXPECT_EQ(scene.triangle_count(), 2u);
    scene.set_instance_transform(a, moved);
    EXPECT_TRUE(scene.ray_tracer().intersect(sideways, 0.0f, 100.0f, hit));
    EXPECT_THROW(scene.set_instance_transform(7, moved), InvalidInput);
}

TEST(Instancing, AMeshShownOnceIsPlacedInRenderSpaceAndBecomesAnInstanceWhenDragged) {
    Scene scene;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    const uint32_t once = add_unit_quad(scene, white);
    const uint32_t shared = add_unit_quad(scene, white);
    const uint32_t far = add_unit_quad(scene, white);
    const uint32_t a = scene.add_instance(once, glm::scale(translation(0, 0, 0), glm::vec3(2.0f)));
    const uint32_t b = scene.add_instance(shared, translation(5, 0, 0));
    const uint32_t c = scene.add_instance(shared, translation(7, 0, 0));
    // 300 of its own sizes from the others: placed in render space it would lose 8 bits, so it stays an instance.
    const uint32_t d = scene.add_instance(far, translation(300, 0, 0));
    const RayTracer& tracer = scene.ray_tracer();
    EXPECT_TRUE(tracer.placed(a));
    EXPECT_FALSE(tracer.placed(b));
    EXPECT_FALSE(tracer.placed(c));
    EXPECT_FALSE(tracer.placed(d));
    // Either way a hit names its instance, and surface_at finds the same point and normal.
    for (const auto& [id, x] : {std::pair{a, 0.7f}, std::pair{b, 5.2f}, std::pair{c, 7.2f}, std::pair{d, 300.2f}}) {
        Hit hit;
        ASSERT_TRUE(tracer.intersect(down_at(x, 0.1f), 0.0f, 100.0f, hit));
        EXPECT_EQ(hit.instance, id);
        const SurfacePoint s = surface_at(scene, down_at(x, 0.1f), hit);
        EXPECT_NEAR(s.position.x, x - scene.origin().x, 1e-4f);
        EXPECT_NEAR(s.geometric_normal.z, 1.0f, 1e-5f);
    }
    // The placed quad's corners (±1 after the scale of 2) set its rounding; an instance keeps its linear part's.
    EXPECT_GE(tracer.rounding_scale(a), 1.0f);
    EXPECT_EQ(tracer.rounding_scale(b), scene.instances()[b].rounding_scale);

    // Moved once, its triangles are re-placed (as a fresh scene would have them); moved again, as a drag does,
    // it becomes an instance of its mesh (further moves refit the top level). Either way the old spot is empty
    // and the new one hit.
    scene.set_instance_transform(a, glm::rotate(translation(0, 2, 0), kPi / 2.0f, glm::vec3(1, 0, 0)));
    EXPECT_EQ(&scene.ray_tracer(), &tracer);  // updated in place
    EXPECT_TRUE(tracer.placed(a));
    Hit hit;
    EXPECT_FALSE(tracer.intersect(down_at(0.7f, 0.1f), 0.0f, 100.0f, hit));
    ASSERT_TRUE(tracer.intersect(Ray{{0.2f, -5.0f, 0.1f}, {0.0f, 1.0f, 0.0f}}, 0.0f, 100.0f, hit));
    EXPECT_NEAR(hit.t, 7.0f, 1e-4f);
    scene.set_instance_transform(a, glm::rotate(translation(0, 3, 0), kPi / 2.0f, glm::vec3(1, 0, 0)));
    EXPECT_EQ(&scene.ray_tracer(), &tracer);
    EXPECT_FALSE(tracer.placed(a));
    EXPECT_EQ(tracer.rounding_scale(a), scene.instances()[a].rounding_scale);
    EXPECT_FALSE(tracer.intersect(down_at(0.7f, 0.1f), 0.0f, 100.0f, hit));
    const Ray sideways{{0.2f, -5.0f, 0.1f}, {0.0f, 1.0f, 0.0f}};
    ASSERT_TRUE(tracer.intersect(sideways, 0.0f, 100.0f, hit));
    EXPECT_EQ(hit.instance, a);
    EXPECT_NEAR(hit.t, 8.0f, 1e-4f);
    // Flattened to zero scale it disappears, and comes back.
    scene.set_instance_transform(a, glm::scale(translation(0, 3, 0), glm::vec3(0.0f)));
    EXPECT_FALSE(scene.ray_tracer().intersect(sideways, 0.0f, 100.0f, hit));
    scene.set_instance_transform(a, glm::rotate(translation(0, 3, 0), kPi / 2.0f, glm::vec3(1, 0, 0)));
    EXPECT_TRUE(scene.ray_tracer().intersect(sideways, 0.0f, 100.0f, hit));
}

TEST(Instancing, EveryInstanceOfAnEmissiveMeshEmits) {
    Scene one, many;
    for (Scene* scene : {&one, &many}) {
        const uint32_t lamp = scene->add_material({"lamp", MaterialKind::diffuse, glm::vec3(0.0f), 1.45f, glm::vec3(3.0f)});
        const uint32_t quad = add_unit_quad(*scene, lamp);
        const int copies = scene == &one ? 1 : 10;
        for (int i = 0; i < copies; ++i) scene->add_instance(quad, glm::scale(translation(2.0f * i, 0, 0), glm::vec3(2.0f)));
    }
    const LightSources a(one), b(many);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    // Flux of a two-sided emitter: 2π · A · L, A = 4 m² after the scale of 2.
    EXPECT_NEAR(a.flux(0).x, 2.0f * kPi * 4.0f * 3.0f, 1e-3f);
    EXPECT_NEAR(b.flux(0).x, 10.0f * a.flux(0).x, 1e-2f);
}

// Cycles 3.x's densities of its light samples, for the weights of its estimate where they matter (a near-mirror
// Multiscatter GGX, mirror_emitter_weight). A rectangle: spherical-rectangle sampling, 1 / its solid angle, which
// on the axis of a 2a × 2b rectangle at distance d is 4 asin(ab / √((a² + d²)(b² + d²))); a far one tends to the
// area density. Emissive triangles: picked by area, sampled by solid angle near and by area far.
TEST(LightSourcesCycles, DensitiesFollowCycles3Sampling) {
    Scene scene;
    const uint32_t lamp = scene.add_material({"lamp", MaterialKind::diffuse, glm::vec3(0.0f), 1.45f, glm::vec3(3.0f)});
    const uint32_t quad = add_unit_quad(scene, lamp);
    scene.add_instance(quad, translation(10.0f, 0, 0));  // 1 m², facing +z (two triangles of 0.5 m²)
    Light area;
    area.kind = LightKind::area;
    area.position = {0, 0, 1};
    area.axis_u = {1, 0, 0};
    area.axis_v = {0, -1, 0};  // shines down
    area.value = glm::vec3(1.0f);
    scene.add_light(area);
    const LightSources sources(scene);
    size_t light = 0;
    while (sources.light(light) == nullptr) ++light;
    // Render space is centred on the scene: o is the world's origin there.
    const glm::vec3 o = sources.light(light)->position - glm::vec3(0, 0, 1);
    // One lamp and emissive triangles: Cycles picks either half the time.
    const double omega = 4.0 * std::asin(0.25 / 1.25);
    EXPECT_NEAR(sources.cycles_lamp_pdf(light, o, {0, 0, 1}), 0.5 / omega, 1e-4);
    EXPECT_NEAR(sources.cycles_lamp_pdf(light, o, glm::normalize(glm::vec3(0.3f, 0.3f, 1))), 0.5 / omega, 1e-4);
    EXPECT_EQ(sources.cycles_lamp_pdf(light, o, {1, 0, 0}), 0.0f);                           // missed
    EXPECT_EQ(sources.cycles_lamp_pdf(light, o + glm::vec3(0, 0, 2), {0, 0, -1}), 0.0f);     // its back
    EXPECT_NEAR(sources.cycles_lamp_pdf(light, o + glm::vec3(0, 0, -999), {0, 0, 1}) / (0.5 * 1000.0 * 1000.0), 1.0,
                1e-3);  // far: the area density
    // The emissive quad's triangle under x: near (its 1.41 m edge against a 0.5 m height), 1 / its solid angle
    // times its share of the picks (0.5 × 0.5 m² / 1 m²); far, the area density d² / (A cos) times the same.
    const glm::vec3 near = o + glm::vec3(10.2f, -0.1f, 0.5f), y = o + glm::vec3(10.2f, -0.1f, 0.0f);
    Hit hit;
    ASSERT_TRUE(scene.ray_tracer().intersect(Ray{near, {0, 0, -1}}, 0.0f, 10.0f, hit));
    const WorldTriangle t = scene.world_triangle(hit.instance, hit.triangle);
    const glm::dvec3 a = glm::dvec3(t.v0 - near), b = glm::dvec3(t.v1 - near), c = glm::dvec3(t.v2 - near);
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double tri_omega = 2.0 * std::atan2(std::fabs(glm::dot(a, glm::cross(b, c))),
                                              la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la);
    EXPECT_NEAR(sources.cycles_emissive_pdf(hit.instance, hit.triangle, near, y), 0.25 / tri_omega, 1e-4);
    const glm::vec3 high = o + glm::vec3(10.2f, -0.1f, 5.0f);
    EXPECT_NEAR(sources.cycles_emissive_pdf(hit.instance, hit.triangle, high, y), 0.25 / 0.5 * 25.0, 1e-3);
}

TEST(Textures, SrgbIsDecodedAndLookupsAreBilinearAndRepeat) {
    // 2 × 1 texture, row 0 at the bottom: black | sRGB 0.5 grey.
    const float pixels[6] = {0, 0, 0, 0.5f, 0.5f, 0.5f};
    const Texture srgb("t", pixels, 2, 1, 3, ColorSpace::srgb);
    const Texture linear("t", pixels, 2, 1, 3, ColorSpace::linear);
    const float decoded = std::pow((0.5f + 0.055f) / 1.055f, 2.4f);  // 0.214
    EXPECT_NEAR(srgb.lookup({0.75f, 0.5f}).x, decoded, 1e-5f);       // the texel's centre
    EXPECT_NEAR(linear.lookup({0.75f, 0.5f}).x, 0.5f, 1e-6f);
    EXPECT_NEAR(linear.lookup({0.5f, 0.5f}).x, 0.25f, 1e-6f);        // halfway between the centres
    EXPECT_NEAR(linear.lookup({1.75f, -3.5f}).x, 0.5f, 1e-5f);       // repeats both ways
    EXPECT_NEAR(linear.lookup({0.0f, 0.5f}).x, 0.25f, 1e-6f);        // wraps across the edge
    const float bad[3] = {NAN, 0, 0};
    EXPECT_THROW(Texture("bad", bad, 1, 1, 3, ColorSpace::linear), InvalidInput);
    EXPECT_THROW(load_texture("missing", "/nonexistent/image.png", ColorSpace::srgb, "texture.path"), InvalidInput);
}

TEST(Textures, SurfaceColourComesFromTheTextureAtTheHitsUv) {
    Scene scene;
    // 2 × 2: red, green (bottom row), blue, white (top row).
    const float pixels[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const uint32_t texture = scene.add_texture(Texture("rgbw", pixels, 2, 2, 3, ColorSpace::linear));
    Material m{"textured", MaterialKind::diffuse, glm::vec3(0.5f), 1.45f, glm::vec3(0.0f)};
    m.texture = static_cast<int32_t>(texture);
    const uint32_t material = scene.add_material(m);
    scene.add_instance(add_unit_quad(scene, material), glm::mat4(1.0f));
    auto colour_at = [&](float x, float y) {
        Hit hit;
        EXPECT_TRUE(scene.ray_tracer().intersect(down_at(x, y), 0.0f, 100.0f, hit));
        const Ray ray = down_at(x, y);
        return shade(scene, surface_at(scene, ray, hit), -ray.direction).lambert;
    };
    // UV (0.25, 0.25) is the red texel's centre: quad point (-0.25, -0.25).
    EXPECT_NEAR(colour_at(-0.25f, -0.25f).x, 1.0f, 1e-4f);
    EXPECT_NEAR(colour_at(0.25f, -0.25f).y, 1.0f, 1e-4f);
    EXPECT_NEAR(colour_at(-0.25f, 0.25f).z, 1.0f, 1e-4f);
    Material dangling = m;
    dangling.texture = 5;
    EXPECT_THROW(scene.add_material(dangling), InvalidInput);
}

TEST(SpotLight, FalloffFluxAndEmissionFollowCycles34) {
    Light spot;
    spot.kind = LightKind::spot;
    spot.value = glm::vec3(10.0f);
    spot.direction = {0, 0, -1};
    spot.spot_size = 1.2f;  // full angle
    spot.spot_blend = 0.4f;
    validate(spot, "spot");
    const float c = std::cos(0.6f);
    // On the axis: I; inside the hard part of the cone: I cos θ; in the blend: smoothstep; outside: 0.
    EXPECT_NEAR(spot.spot_attenuation({0, 0, -1}), 1.0f, 1e-6f);
    const float theta = 0.2f;
    EXPECT_NEAR(spot.spot_attenuation({std::sin(theta), 0, -std::cos(theta)}), std::cos(theta), 1e-5f);
    EXPECT_EQ(spot.spot_attenuation({std::sin(0.61f), 0, -std::cos(0.61f)}), 0.0f);
    const float in_blend = std::acos(c + 0.5f * (1.0f - c) * 0.4f);  // halfway through the blend: smoothstep 0.5
    EXPECT_NEAR(spot.spot_attenuation({std::sin(in_blend), 0, -std::cos(in_blend)}), 0.5f * std::cos(in_blend), 1e-4f);

    // Flux = ∫ I(ω) dω: numerically over θ.
    double integral = 0.0;
    const int steps = 200000;
    for (int i = 0; i < steps; ++i) {
        const double t = (i + 0.5) * kPi / steps;
        integral += spot.spot_attenuation({static_cast<float>(std::sin(t)), 0, static_cast<float>(-std::cos(t))}) *
                    2.0 * kPi * std::sin(t) * (kPi / steps);
    }
    const float flux = light_flux(spot, 1.0f).x;
    EXPECT_NEAR(flux, 10.0 * integral, 1e-3 * flux);

    // Emitted photons: inside the cone, mean power = flux.
    double power = 0.0;
    Rng rng(1, RngDomain::photon, 0);
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        const EmissionSample e = sample_light_emission(spot, glm::vec3(0), 1.0f, rng.uniform(), rng.uniform(),
                                                       rng.uniform(), rng.uniform());
        ASSERT_GE(-e.direction.z, c - 1e-5f);
        power += e.power.x;
    }
    EXPECT_NEAR(power / n, flux, 0.01 * flux);
    spot.spot_blend = 2.0f;
    EXPECT_THROW(validate(spot, "spot"), InvalidInput);
}

TEST(AreaLight, EllipseHasItsAreaAndItsShape) {
    Light disk;
    disk.kind = LightKind::area;
    disk.axis_u = {2, 0, 0};
    disk.axis_v = {0, 1, 0};
    disk.ellipse = true;
    disk.value = glm::vec3(1.0f);
    EXPECT_NEAR(disk.area(), kPi / 4.0f * 2.0f, 1e-5f);
    EXPECT_NEAR(light_flux(disk, 1.0f).x, kPi * disk.area(), 1e-4f);
    Rng rng(2, RngDomain::photon, 0);
    for (int i = 0; i < 10000; ++i) {
        const EmissionSample e = sample_light_emission(disk, glm::vec3(0), 1.0f, rng.uniform(), rng.uniform(),
                                                       rng.uniform(), rng.uniform());
        ASSERT_LE(e.origin.x * e.origin.x + 4.0f * e.origin.y * e.origin.y, 1.0f + 1e-4f);  // (x/1)² + (y/0.5)²
    }
}

TEST(RayVisibility, CameraInvisibleObjectsStillCastShadowsAndHoldoutsCutOut) {
    Scene scene;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    Material cutout{"holdout", MaterialKind::diffuse, glm::vec3(0.0f), 1.45f, glm::vec3(0.0f)};
    cutout.holdout = true;
    const uint32_t holdout = scene.add_material(cutout);
    const uint32_t floor = add_unit_quad(scene, white);
    const uint32_t hidden = scene.add_instance(floor, glm::scale(glm::mat4(1.0f), glm::vec3(20.0f)), "floor",
                                               kShadowRays | kIndirectRays);
    Hit hit;
    EXPECT_FALSE(scene.ray_tracer().intersect(down_at(0, 0), 0.0f, 100.0f, hit, kCameraRays));
    EXPECT_TRUE(scene.ray_tracer().occluded(down_at(0, 0), 0.0f, 100.0f, kShadowRays));
    EXPECT_TRUE(scene.ray_tracer().intersect(down_at(0, 0), 0.0f, 100.0f, hit, kIndirectRays));
    (void)hidden;

    // A holdout quad seen by the camera: alpha 0 and no view sample there.
    scene.add_instance(add_unit_quad(scene, holdout), translation(0, 0, 1));
    const Camera camera = test::look_at({0, 0, 6}, {0, 0, 0}, 16, 16, 5.0f, {0, 1, 0});
    RenderControl control;
    Stats stats;
    const ViewSamples samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    EXPECT_EQ(samples.alpha[8 * 16 + 8], 0.0f);
    EXPECT_TRUE(samples.samples.empty());
}

TEST(CameraClip, RaysStopAtTheFarClipPlane) {
    Scene scene;
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    scene.add_instance(add_unit_quad(scene, white), glm::scale(glm::mat4(1.0f), glm::vec3(50.0f)));
    const glm::mat4 to_world = glm::inverse(glm::lookAt(glm::vec3(0, 0, 6), glm::vec3(0), glm::vec3(0, 1, 0)));
    RenderControl control;
    Stats stats;
    for (float far : {5.0f, 7.0f}) {
        const Camera camera(to_world, test::perspective(40.0f, 1.0f, 0.1f, far), 8, 8);
        EXPECT_NEAR(camera.far_clip(), far, 1e-3f);
        const ViewSamples samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
        EXPECT_EQ(samples.samples.size(), far > 6.0f ? 64u : 0u) << "far clip " << far;
    }
}

}  // namespace
