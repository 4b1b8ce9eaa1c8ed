// The Python face of the native core: numpy arrays and plain values in, numpy arrays and dicts out.
// Thin on purpose: validation of meaning lives in the core; here we only check that arrays have the shape
// and kind promised, and name the field when they do not.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <sstream>
#include <string>

#include "arrays.h"
#include "background.h"
#include "bindings.h"
#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"

namespace py = pybind11;
using namespace pybind11::literals;

using namespace ps_py;

namespace {

// Python ints of any sign reach the core's unsigned pass count only through here, so -1 is named, not wrapped.
uint32_t iteration_count(int64_t passes) {
    if (passes < 0 || passes > 1'000'000)
        throw ps::InvalidInput("passes", "must be in [0, 1000000] (0 = until time_limit), got " + std::to_string(passes));
    return static_cast<uint32_t>(passes);
}

ps::RenderSettings make_settings(uint64_t photons, float radius, const std::string& method, int max_bounces,
                                 uint64_t seed, int threads, int direct_samples, float normal_tolerance,
                                 float plane_distance, const std::string& kernel, int directional_level,
                                 int64_t passes, double time_limit, float alpha, bool guide_photons,
                                 bool caustics_pass, bool transparent,
                                 uint64_t memory_budget, float aimed_photons, bool boundary_correction) {
    ps::RenderSettings s;
    s.photons = photons;
    s.radius = radius;
    s.method = ps::splat_method_from_string(method);
    s.max_bounces = max_bounces;
    s.seed = seed;
    s.threads = threads;
    s.direct_samples = direct_samples;
    s.normal_tolerance = normal_tolerance;
    s.plane_distance = plane_distance;
    s.kernel = ps::kernel_from_string(kernel);
    s.directional_level = directional_level;
    s.memory_budget = memory_budget;
    s.iterations = iteration_count(passes);
    s.time_limit = time_limit;
    s.alpha = alpha;
    s.guide_photons = guide_photons;
    s.caustics_pass = caustics_pass;
    s.transparent = transparent;
    s.aimed_photons = aimed_photons;
    s.boundary_correction = boundary_correction;
    ps::validate(s);
    return s;
}

// Renders one frame off the GIL (see background.h); returns (image, stats[, passes]). Without passes only the
// combined image is made: the film holds no other output, and no caustic splat is run.
py::object render(const ps::Scene& scene, const ps::Camera& camera, const ps::RenderSettings& settings,
                  const py::object& progress, bool passes) {
    ps::validate(settings);
    ps::RenderSettings own = settings;
    if (!passes) {
        own.outputs = ps::film_bit(ps::FilmOutput::combined);
        own.caustics_pass = false;
    }
    const ps::RenderResult r = run_in_background<ps::RenderResult>(
        progress, [&](ps::RenderControl& control) { return ps::render(scene, camera, own, control); });
    py::array_t<float> image = image_array(r.rgba(), r.height(), r.width(), 4);
    if (!passes) return py::make_tuple(image, stats_dict(r.stats));
    return py::make_tuple(image, stats_dict(r.stats), pass_images(r));
}

}  // namespace

PYBIND11_MODULE(_core, m) {
    m.doc() = "Photon Splat native core: scene, camera, render settings and render().";
    m.attr("__version__") = "0.1.0";
    m.attr("METHODS") = py::tuple(py::cast(ps::splat_method_names()));
    m.attr("KERNELS") = py::make_tuple("uniform", "epanechnikov");

    static py::exception<ps::Cancelled> cancelled(m, "Cancelled", PyExc_RuntimeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ps::Cancelled& e) {
            cancelled(e.what());
        } catch (const ps::InvalidInput& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });

    py::class_<ps::Scene>(m, "Scene", "Triangle meshes, materials, lights and a background; validated on entry.")
        .def(py::init<>())
        .def(
            "add_material",
            [](ps::Scene& s, const std::string& name, const std::string& kind, const py::object& color, float ior,
               const py::object& emission, float roughness, int texture, bool holdout) {
                ps::Material mat;
                mat.name = name;
                mat.kind = ps::material_kind_from_string(kind);
                mat.color = vec3(color, "material '" + name + "'.color");
                mat.ior = ior;
                mat.emission = vec3(emission, "material '" + name + "'.emission");
                mat.roughness = roughness;  // validated by the core: finite, in [0, 1]
                mat.texture = texture;      // validated by the scene: -1 or an existing texture
                mat.holdout = holdout;
                return s.add_material(mat);
            },
            "name"_a, "kind"_a = "diffuse", "color"_a = py::make_tuple(0.8, 0.8, 0.8), "ior"_a = 1.45f,
            "emission"_a = py::make_tuple(0.0, 0.0, 0.0), "roughness"_a = 0.5f, "texture"_a = -1, "holdout"_a = false,
            "Adds a material ('diffuse', 'mirror', 'glass' or 'glossy'); returns its index for material_ids. "
            "roughness (glossy only, Blender's, in [0, 1]): GGX with alpha = roughness^2; <= 0.05 is a mirror. "
            "texture: index of add_texture() whose colour at the hit's UV replaces color (-1: none). "
            "holdout: cut out of the image where the camera sees it (alpha 0), black for other rays.")
        .def(
            "add_point_light",
            [](ps::Scene& s, const std::string& name, const py::object& position, const py::object& intensity,
               float radius) {
                ps::Light l;
                l.name = name;
                l.kind = ps::LightKind::point;
                const glm::dvec3 p = dvec3(position, "point light '" + name + "'.position");
                l.value = vec3(intensity, "point light '" + name + "'.intensity");
                l.radius = radius;
                s.add_light(l, p);
            },
            "name"_a, "position"_a, "intensity"_a, "radius"_a = 0.0f, "Isotropic point light; intensity in W/sr.")
        .def(
            "add_sun_light",
            [](ps::Scene& s, const std::string& name, const py::object& direction, const py::object& irradiance,
               float angle) {
                ps::Light l;
                l.name = name;
                l.kind = ps::LightKind::sun;
                l.direction = vec3(direction, "sun light '" + name + "'.direction");
                l.value = vec3(irradiance, "sun light '" + name + "'.irradiance");
                l.angle = angle;
                s.add_light(l);
            },
            "name"_a, "direction"_a, "irradiance"_a, "angle"_a = 0.0f,
            "Distant light travelling along direction; irradiance in W/m²; angle = full angular diameter.")
        .def(
            "add_area_light",
            [](ps::Scene& s, const std::string& name, const py::object& center, const py::object& axis_u,
               const py::object& axis_v, const py::object& radiance, const std::string& shape) {
                ps::Light l;
                l.name = name;
                l.kind = ps::LightKind::area;
                const glm::dvec3 c = dvec3(center, "area light '" + name + "'.center");
                l.axis_u = vec3(axis_u, "area light '" + name + "'.axis_u");
                l.axis_v = vec3(axis_v, "area light '" + name + "'.axis_v");
                l.value = vec3(radiance, "area light '" + name + "'.radiance");
                if (shape != "rectangle" && shape != "ellipse")
                    throw ps::InvalidInput("area light '" + name + "'.shape",
                                           "must be 'rectangle' or 'ellipse', got '" + shape + "'");
                l.ellipse = shape == "ellipse";
                s.add_light(l, c);
            },
            "name"_a, "center"_a, "axis_u"_a, "axis_v"_a, "radiance"_a, "shape"_a = "rectangle",
            "One-sided rectangle with full edge vectors u, v (or, shape='ellipse', the ellipse inscribed in it), "
            "emitting radiance towards cross(u, v).")
        .def(
            "set_background", [](ps::Scene& s, const py::object& radiance) { s.set_background(vec3(radiance, "background")); },
            "radiance"_a)
        .def_property_readonly("triangle_count", &ps::Scene::triangle_count,
                               "Triangles in the world: each instance counts its mesh's.")
        .def_property_readonly("dropped_triangles", &ps::Scene::dropped_triangles,
                               "Degenerate (zero-area) triangles dropped on entry.")
        .def_property_readonly("material_count", [](const ps::Scene& s) { return s.materials().size(); })
        .def_property_readonly("light_count", [](const ps::Scene& s) { return s.lights().size(); });

    py::class_<ps::Camera>(m, "Camera", "Camera from a (4,4) camera-to-world matrix (read in float64) and an "
                                        "OpenGL-style projection.")
        .def(py::init([](const py::object& to_world, const py::object& projection, const py::object& width,
                         const py::object& height) {
                 return ps::Camera(dmat4(to_world, "camera.to_world"), mat4(projection, "camera.projection"),
                                   positive_int(width, "camera.width"), positive_int(height, "camera.height"));
             }),
             "to_world"_a, "projection"_a, "width"_a, "height"_a)
        .def_property_readonly("width", &ps::Camera::width)
        .def_property_readonly("height", &ps::Camera::height)
        .def_property_readonly("orthographic", &ps::Camera::orthographic);

    py::class_<ps::RenderSettings>(m, "RenderSettings", "Settings of one render; validated on construction.")
        .def(py::init(&make_settings), "photons"_a = 200000, "radius"_a = 0.0f, "method"_a = "cluster_cone",
             "max_bounces"_a = 8, "seed"_a = 0, "threads"_a = 0, "direct_samples"_a = 4, "normal_tolerance"_a = 60.0f,
             "plane_distance"_a = 0.0f, "kernel"_a = "uniform", "directional_level"_a = -1, "passes"_a = 1,
             "time_limit"_a = 0.0, "alpha"_a = 2.0f / 3.0f, "guide_photons"_a = true, "caustics_pass"_a = false,
             "transparent"_a = false, "memory_budget"_a = 0, "aimed_photons"_a = ps::RenderSettings().aimed_photons,
             "boundary_correction"_a = true)
        .def_readwrite("photons", &ps::RenderSettings::photons)
        .def_readwrite("radius", &ps::RenderSettings::radius)
        .def_property(
            "method", [](const ps::RenderSettings& s) { return std::string(ps::to_string(s.method)); },
            [](ps::RenderSettings& s, const std::string& v) { s.method = ps::splat_method_from_string(v); })
        .def_readwrite("max_bounces", &ps::RenderSettings::max_bounces)
        .def_readwrite("seed", &ps::RenderSettings::seed)
        .def_readwrite("threads", &ps::RenderSettings::threads)
        .def_readwrite("direct_samples", &ps::RenderSettings::direct_samples)
        .def_readwrite("normal_tolerance", &ps::RenderSettings::normal_tolerance)
        .def_readwrite("plane_distance", &ps::RenderSettings::plane_distance)
        .def_property(
            "kernel", [](const ps::RenderSettings& s) { return std::string(ps::to_string(s.kernel)); },
            [](ps::RenderSettings& s, const std::string& v) { s.kernel = ps::kernel_from_string(v); })
        .def_readwrite("directional_level", &ps::RenderSettings::directional_level)
        .def_readwrite("memory_budget", &ps::RenderSettings::memory_budget,
                       "bytes the render may hold; 0 = 3/4 of this machine's (or container's) memory")
        .def_property(
            "passes", [](const ps::RenderSettings& s) { return s.iterations; },
            [](ps::RenderSettings& s, int64_t v) { s.iterations = iteration_count(v); },
            "Progressive passes; 1 = the one-shot method, 0 = until time_limit")
        .def_readwrite("time_limit", &ps::RenderSettings::time_limit,
                       "Seconds of progressive rendering; 0 = none. A pass predicted to end past it is not started")
        .def_readwrite("alpha", &ps::RenderSettings::alpha,
                       "Radius shrink of progressive passes: r_i^2 = r_(i-1)^2 (i-1+alpha)/i, in (0, 1]")
        .def_readwrite("guide_photons", &ps::RenderSettings::guide_photons,
                       "Emit sun photons where pilot paths found them stored; unbiased (default True)")
        .def_readwrite("aimed_photons", &ps::RenderSettings::aimed_photons,
                       "Extra photons per pass aimed at mirror and glass objects (point, spot and area lights), as a "
                       "fraction of photons; they add caustic photons only, weighted so the image stays unbiased. "
                       "0 = off.")
        .def_readwrite("boundary_correction", &ps::RenderSettings::boundary_correction,
                       "Divide each view sample's splatted light by the part of its kernel disc that lies on a "
                       "like-facing surface: corners, edges and thin parts lose no light to the kernel (default True; glossy "
                       "samples and directional's approximate passes are left as they are)")
        .def_readwrite("caustics_pass", &ps::RenderSettings::caustics_pass,
                       "Also splat the caustic photons (light -> specular+ -> diffuse) alone: passes['caustics']")
        .def_readwrite("transparent", &ps::RenderSettings::transparent,
                       "Film transparency: alpha 0 and no background where camera rays escape to the world")
        .def("__repr__", [](const ps::RenderSettings& s) {
            std::ostringstream o;
            o << "RenderSettings(photons=" << s.photons << ", radius=" << s.radius << ", method='"
              << ps::to_string(s.method) << "', max_bounces=" << s.max_bounces << ", seed=" << s.seed
              << ", threads=" << s.threads << ", direct_samples=" << s.direct_samples << ", kernel='"
              << ps::to_string(s.kernel) << "', directional_level=" << s.directional_level
              << ", passes=" << s.iterations << ", time_limit=" << s.time_limit << ", alpha=" << s.alpha
              << ", guide_photons=" << (s.guide_photons ? "True" : "False") << ", aimed_photons=" << s.aimed_photons
              << ", boundary_correction=" << (s.boundary_correction ? "True" : "False")
              << ", caustics_pass=" << (s.caustics_pass ? "True" : "False")
              << ", transparent=" << (s.transparent ? "True" : "False") << ", memory_budget=" << s.memory_budget << ")";
            return o.str();
        });

    m.def("render", &render, "scene"_a, "camera"_a, "settings"_a = ps::RenderSettings(), "progress"_a = py::none(),
          "passes"_a = false,
          "Renders one frame. Returns (image, stats): image float32 (H, W, 4) linear radiance, row 0 at the top; "
          "with passes=True also a dict of 'emission', 'direct', 'indirect', 'normal' (H, W, 3), 'depth' (H, W, 1) "
          "and, with settings.caustics_pass, 'caustics' (H, W, 3). progress(stage, fraction) "
          "is called about 10× a second on the calling thread; returning True cancels (raises Cancelled). "
          "settings.iterations != 1 or a time_limit render progressively (the mean of the passes); a cancel after "
          "the first pass returns the mean so far with stats['values']['cancelled'] = 1.");

    m.def("default_memory_budget", &ps::default_memory_budget,
          "Bytes a render may hold when RenderSettings.memory_budget is 0: 3/4 of available memory.");

    m.def(
        "automatic_radius",
        [](const ps::Scene& scene, const ps::Camera& camera, uint64_t photons) {
            py::gil_scoped_release release;
            return ps::automatic_radius(scene, camera, photons);
        },
        "scene"_a, "camera"_a, "photons"_a,
        "The first kernel radius of a progressive render when settings.radius is 0 and the boundary correction "
        "does not cover it (off, or method 'directional'): the scene's size scaled for the photon count, shrunk "
        "(to a quarter at most) where the boundary bias of what the camera sees (boundary_loss) calls for it. "
        "One-pass renders, and progressive ones with the correction (the default), use the unshrunk radius.");
    m.def(
        "boundary_loss",
        [](const ps::Scene& scene, const ps::Camera& camera, float radius) {
            if (!(std::isfinite(radius) && radius > 0.0f))
                throw ps::InvalidInput("radius", "must be finite and > 0, got " + std::to_string(radius));
            py::gil_scoped_release release;
            return ps::boundary_loss(scene, camera, radius);
        },
        "scene"_a, "camera"_a, "radius"_a,
        "The expected fraction of a kernel disc of this radius that falls off the surface it is centred on, "
        "over what the camera sees (0..1): the boundary bias that limits the automatic radius.");

    bind_images(m);
    bind_metrics(m);
    bind_reference(m);
    bind_translation(m);
    bind_progressive(m);
    bind_scene_updates(m);
}
