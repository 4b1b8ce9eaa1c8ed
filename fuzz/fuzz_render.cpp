// libFuzzer target over the entry points a script or the add-on reaches: Scene::add_material / add_mesh /
// add_light / set_background, the Camera constructor, validate(RenderSettings) and render(). The input bytes are
// decoded into a small scene (<= 4 materials, <= 3 meshes of <= 12 vertices and triangles, some instanced twice,
// <= 3 lights), a camera of <= 12×12 pixels and settings with <= 1500 photons and <= 2 progressive iterations, so
// that one input renders quickly.
//
// What counts as a failure: a crash or sanitizer report (the build adds address and undefined), an exception other
// than InvalidInput (bad input must be refused naming the field), or a non-finite pixel from a render the core
// accepted; a failure aborts. Built with clang and run by scripts/sanitize.sh from the seed corpus
// fuzz/corpus.tar.gz and the reproducers in fuzz/regressions/; fuzz/replay.cpp runs this same function on given
// files without libFuzzer (the ctest tests FuzzRegression.*).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <string>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <glm/mat4x4.hpp>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"

namespace {

using namespace ps;

// A float that is usually ordinary but may be 0, negative, huge, tiny, NaN or infinite.
float any_float(FuzzedDataProvider& in, float typical) {
    switch (in.ConsumeIntegralInRange<int>(0, 9)) {
        case 0: return 0.0f;
        case 1: return std::nanf("");
        case 2: return in.ConsumeBool() ? INFINITY : -INFINITY;
        case 3: return in.ConsumeBool() ? 3e38f : -3e38f;
        case 4: return in.ConsumeBool() ? 1e-30f : -1e-30f;
        default: return in.ConsumeFloatingPointInRange<float>(-typical, typical);
    }
}

glm::vec3 any_vec3(FuzzedDataProvider& in, float typical) {
    return {any_float(in, typical), any_float(in, typical), any_float(in, typical)};
}

// Mostly in [0, 1], sometimes anything.
glm::vec3 colour(FuzzedDataProvider& in) {
    if (in.ConsumeIntegralInRange<int>(0, 7) == 0) return any_vec3(in, 10.0f);
    return {in.ConsumeProbability<float>(), in.ConsumeProbability<float>(), in.ConsumeProbability<float>()};
}

// Up to max_count items named prefix0, prefix1, ..., each of one of the first `kinds` kinds; fill sets the other
// fields from the input and add hands the item to the scene, which may refuse it (InvalidInput: left out).
template <class Item, class Fill, class Add>
void add_named(FuzzedDataProvider& in, int max_count, const char* prefix, int kinds, Fill fill, Add add) {
    const int count = in.ConsumeIntegralInRange<int>(0, max_count);
    for (int i = 0; i < count; ++i) {
        Item item;
        item.name = prefix + std::to_string(i);
        item.kind = static_cast<decltype(item.kind)>(in.ConsumeIntegralInRange<int>(0, kinds - 1));
        fill(item);
        try {
            add(item);
        } catch (const InvalidInput&) {
        }
    }
}

void add_materials(FuzzedDataProvider& in, Scene& scene) {
    const auto fill = [&in](Material& m) {
        m.color = colour(in);
        m.ior = in.ConsumeBool() ? 1.5f : any_float(in, 3.0f);
        m.emission = in.ConsumeIntegralInRange<int>(0, 3) == 0 ? colour(in) : glm::vec3(0.0f);
        m.roughness = in.ConsumeBool() ? in.ConsumeProbability<float>() : any_float(in, 2.0f);
    };
    add_named<Material>(in, 4, "m", 4, fill, [&scene](const Material& m) { scene.add_material(m); });
}

void add_meshes(FuzzedDataProvider& in, Scene& scene) {
    const int count = in.ConsumeIntegralInRange<int>(0, 3);
    for (int i = 0; i < count; ++i) {
        const size_t vertices = in.ConsumeIntegralInRange<size_t>(0, 12);
        const size_t triangles = in.ConsumeIntegralInRange<size_t>(0, 12);
        std::vector<float> v(3 * vertices), n(3 * vertices);
        for (float& x : v) x = in.ConsumeIntegralInRange<int>(0, 15) == 0 ? any_float(in, 1e6f) : in.ConsumeFloatingPointInRange<float>(-2.0f, 2.0f);
        for (float& x : n) x = in.ConsumeFloatingPointInRange<float>(-1.0f, 1.0f);
        std::vector<int32_t> t(3 * triangles), ids(triangles);
        for (int32_t& x : t) x = in.ConsumeIntegralInRange<int32_t>(-1, static_cast<int32_t>(vertices));
        for (int32_t& x : ids) x = in.ConsumeIntegralInRange<int32_t>(-1, 4);
        MeshInput mesh;
        mesh.name = "mesh" + std::to_string(i);
        mesh.vertices = v.data();
        mesh.vertex_count = vertices;
        mesh.triangles = t.data();
        mesh.triangle_count = triangles;
        if (in.ConsumeBool()) mesh.normals = n.data();
        if (in.ConsumeBool()) mesh.material_ids = ids.data();
        if (in.ConsumeBool()) {
            for (int c = 0; c < 4; ++c)
                for (int r = 0; r < 3; ++r) mesh.transform[c][r] = any_float(in, 3.0f);
        }
        try {
            scene.add_mesh(mesh);
            // Sometimes a second instance of the mesh just added, anywhere.
            if (!scene.meshes().empty() && in.ConsumeIntegralInRange<int>(0, 3) == 0) {
                glm::mat4 to_world(1.0f);
                for (int c = 0; c < 4; ++c)
                    for (int r = 0; r < 3; ++r) to_world[c][r] = any_float(in, 3.0f);
                scene.add_instance(static_cast<uint32_t>(scene.meshes().size() - 1), to_world, mesh.name + "_copy");
            }
        } catch (const InvalidInput&) {
        }
    }
}

void add_lights(FuzzedDataProvider& in, Scene& scene) {
    const auto fill = [&in](Light& light) {
        light.value = in.ConsumeBool() ? 50.0f * colour(in) : any_vec3(in, 1e3f);
        light.position = in.ConsumeBool() ? glm::vec3(0.0f, 0.0f, 1.5f) : any_vec3(in, 3.0f);
        light.direction = in.ConsumeBool() ? glm::vec3(0.0f, 0.0f, -1.0f) : any_vec3(in, 1.0f);
        light.radius = in.ConsumeBool() ? 0.0f : any_float(in, 1.0f);
        light.angle = in.ConsumeBool() ? 0.0f : any_float(in, 4.0f);
        light.axis_u = in.ConsumeBool() ? glm::vec3(1.0f, 0.0f, 0.0f) : any_vec3(in, 2.0f);
        light.axis_v = in.ConsumeBool() ? glm::vec3(0.0f, 1.0f, 0.0f) : any_vec3(in, 2.0f);
    };
    add_named<Light>(in, 3, "light", 3, fill, [&scene](const Light& light) { scene.add_light(light); });
    try {
        scene.set_background(in.ConsumeBool() ? glm::vec3(0.0f) : colour(in));
    } catch (const InvalidInput&) {
    }
}

// A camera at (0, −4, 1) looking at +y, perspective or orthographic, or (sometimes) arbitrary matrices.
Camera make_camera(FuzzedDataProvider& in) {
    const int width = in.ConsumeIntegralInRange<int>(in.ConsumeBool() ? -2 : 1, 12);
    const int height = in.ConsumeIntegralInRange<int>(in.ConsumeBool() ? -2 : 1, 12);
    glm::mat4 to_world(1.0f);
    to_world[1] = glm::vec4(0, 0, 1, 0);
    to_world[2] = glm::vec4(0, -1, 0, 0);
    to_world[3] = glm::vec4(0, -4, 1, 1);
    glm::mat4 projection(0.0f);
    const float near = in.ConsumeBool() ? 0.1f : any_float(in, 1.0f), far = 100.0f;
    if (in.ConsumeBool()) {
        const float f = in.ConsumeBool() ? 2.7f : any_float(in, 10.0f);
        projection[0][0] = f * height / std::max(width, 1);
        projection[1][1] = f;
        projection[2][2] = (far + near) / (near - far);
        projection[3][2] = 2.0f * far * near / (near - far);
        projection[2][3] = -1.0f;
    } else {
        projection = glm::mat4(1.0f);
        projection[0][0] = projection[1][1] = in.ConsumeBool() ? 0.5f : any_float(in, 2.0f);
        projection[2][2] = -2.0f / (far - near);
        projection[3][2] = -(far + near) / (far - near);
    }
    if (in.ConsumeIntegralInRange<int>(0, 7) == 0)
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) to_world[c][r] = any_float(in, 5.0f);
    return Camera(to_world, projection, width, height);
}

RenderSettings make_settings(FuzzedDataProvider& in) {
    RenderSettings s;
    s.photons = in.ConsumeIntegralInRange<uint64_t>(0, 1500);
    s.radius = in.ConsumeBool() ? 0.0f : any_float(in, 5.0f);
    s.method = static_cast<SplatMethod>(in.ConsumeIntegralInRange<int>(0, 5));
    s.max_bounces = in.ConsumeIntegralInRange<int>(-1, 16);
    s.seed = in.ConsumeIntegral<uint64_t>();
    s.threads = in.ConsumeIntegralInRange<int>(0, 2);
    s.direct_samples = in.ConsumeIntegralInRange<int>(0, 4);
    s.normal_tolerance = in.ConsumeBool() ? 60.0f : any_float(in, 200.0f);
    s.plane_distance = in.ConsumeBool() ? 0.0f : any_float(in, 1.0f);
    s.kernel = in.ConsumeBool() ? Kernel::uniform : Kernel::epanechnikov;
    s.directional_level = in.ConsumeIntegralInRange<int>(-2, 8);
    s.memory_budget = in.ConsumeBool() ? 0 : in.ConsumeIntegralInRange<uint64_t>(0, uint64_t(64) << 20);
    s.iterations = in.ConsumeIntegralInRange<uint32_t>(0, 2);  // 0 needs a time limit; 2 runs the progressive path
    s.time_limit = in.ConsumeBool() ? 0.0 : 0.05;
    s.caustics_pass = in.ConsumeBool();
    s.transparent = in.ConsumeBool();
    return s;
}

// What a failing input decoded to, for the report.
void describe(const Scene& scene, const Camera& camera, const RenderSettings& s) {
    std::fprintf(stderr, "camera %dx%d ortho %d near %g; photons %llu radius %g method %s bounces %d tau %g kappa %g\n",
                 camera.width(), camera.height(), int(camera.orthographic()), camera.near_clip(),
                 (unsigned long long)s.photons, s.radius, to_string(s.method), s.max_bounces, s.normal_tolerance,
                 s.plane_distance);
    for (const Material& m : scene.materials())
        std::fprintf(stderr, "material %s kind %d color %g %g %g ior %g emission %g %g %g roughness %g\n",
                     m.name.c_str(), int(m.kind), m.color.x, m.color.y, m.color.z, m.ior, m.emission.x, m.emission.y,
                     m.emission.z, m.roughness);
    for (const Light& l : scene.lights())
        std::fprintf(stderr, "light %s kind %d value %g %g %g pos %g %g %g dir %g %g %g radius %g angle %g u %g %g %g v %g %g %g\n",
                     l.name.c_str(), int(l.kind), l.value.x, l.value.y, l.value.z, l.position.x, l.position.y,
                     l.position.z, l.direction.x, l.direction.y, l.direction.z, l.radius, l.angle, l.axis_u.x,
                     l.axis_u.y, l.axis_u.z, l.axis_v.x, l.axis_v.y, l.axis_v.z);
    for (uint32_t i = 0; i < scene.instances().size(); ++i) {
        const MeshData& mesh = scene.meshes()[scene.instances()[i].mesh];
        for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
            const WorldTriangle w = scene.world_triangle(i, t);
            std::fprintf(stderr, "instance %u triangle (%g %g %g) (%g %g %g) (%g %g %g)\n", i, w.v0.x, w.v0.y, w.v0.z,
                         w.v1.x, w.v1.y, w.v1.z, w.v2.x, w.v2.y, w.v2.z);
        }
    }
    const glm::vec3 b = scene.background();
    std::fprintf(stderr, "background %g %g %g\n", b.x, b.y, b.z);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    FuzzedDataProvider in(data, size);
    Scene scene;
    add_materials(in, scene);
    add_meshes(in, scene);
    add_lights(in, scene);
    try {
        const Camera camera = make_camera(in);
        const RenderSettings settings = make_settings(in);
        RenderControl control;
        const RenderResult result = render(scene, camera, settings, control);
        const std::vector<float>& rgba = result.rgba();
        for (size_t i = 0; i < rgba.size(); ++i) {
            if (!std::isfinite(rgba[i])) {
                const size_t p = i / 4, c = std::min<size_t>(i % 4, 2);
                std::fprintf(stderr, "non-finite pixel %zu from an accepted render: emission %g direct %g indirect %g\n",
                             p, result.film[FilmOutput::emission][3 * p + c], result.film[FilmOutput::direct][3 * p + c],
                             result.film[FilmOutput::indirect][3 * p + c]);
                describe(scene, camera, settings);
                std::abort();
            }
        }
    } catch (const InvalidInput&) {
        // Refused with a message naming the field: the contract.
    }
    return 0;
}
