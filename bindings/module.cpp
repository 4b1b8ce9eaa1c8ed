// The Python face of the native core: numpy arrays and plain values in, numpy arrays and dicts out.
// Thin on purpose: validation of meaning lives in the core; here we only check that arrays have the shape
// and kind promised, and name the field when they do not.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

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

void add_mesh(ps::Scene& scene, const std::string& name, const py::object& vertices_obj,
              const py::object& triangles_obj, const py::object& normals_obj, const py::object& material_ids_obj,
              const py::object& transform_obj) {
    const std::string where = "mesh '" + name + "'";
    auto vertices = float_array(vertices_obj, where + ".vertices");
    require_shape(vertices, {-1, 3}, where + ".vertices", "(N, 3)");
    auto triangles = index_array(triangles_obj, where + ".triangles");
    require_shape(triangles, {-1, 3}, where + ".triangles", "(M, 3)");
    ps::MeshInput mesh;
    mesh.name = name;
    mesh.vertices = vertices.data();
    mesh.vertex_count = static_cast<size_t>(vertices.shape(0));
    mesh.triangles = triangles.data();
    mesh.triangle_count = static_cast<size_t>(triangles.shape(0));
    py::array_t<float, py::array::c_style> normals;
    if (!normals_obj.is_none()) {
        normals = float_array(normals_obj, where + ".normals");
        if (normals.ndim() == 3) {
            require_shape(normals, {static_cast<py::ssize_t>(mesh.triangle_count), 3, 3}, where + ".normals",
                          "(M, 3, 3) per corner or (N, 3) per vertex");
            mesh.normals_per_corner = true;
        } else {
            require_shape(normals, {static_cast<py::ssize_t>(mesh.vertex_count), 3}, where + ".normals",
                          "(N, 3) per vertex or (M, 3, 3) per corner");
        }
        mesh.normals = normals.data();
    }
    py::array_t<int32_t, py::array::c_style> material_ids;
    if (!material_ids_obj.is_none()) {
        material_ids = index_array(material_ids_obj, where + ".material_ids");
        require_shape(material_ids, {static_cast<py::ssize_t>(mesh.triangle_count)}, where + ".material_ids", "(M,)");
        mesh.material_ids = material_ids.data();
    }
    if (!transform_obj.is_none()) mesh.transform = mat4(transform_obj, where + ".transform");
    scene.add_mesh(mesh);  // validates values: NaN, index ranges, material ids
}

ps::RenderSettings make_settings(uint64_t photons, float radius, const std::string& method, int max_bounces,
                                 uint64_t seed, int threads, int direct_samples, float normal_tolerance,
                                 float plane_distance, const std::string& kernel, int directional_level,
                                 uint64_t memory_budget) {
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
    ps::validate(s);
    return s;
}

// Renders one frame off the GIL (see background.h); returns (image, stats[, passes]).
py::object render(const ps::Scene& scene, const ps::Camera& camera, const ps::RenderSettings& settings,
                  const py::object& progress, bool passes) {
    ps::validate(settings);
    const ps::RenderResult r = run_in_background<ps::RenderResult>(
        progress, [&](ps::RenderControl& control) { return ps::render(scene, camera, settings, control); });
    py::array_t<float> image = image_array(r.rgba, r.height, r.width, 4);
    if (!passes) return py::make_tuple(image, stats_dict(r.stats));
    py::dict components("emission"_a = image_array(r.emission, r.height, r.width, 3),
                        "direct"_a = image_array(r.direct, r.height, r.width, 3),
                        "indirect"_a = image_array(r.indirect, r.height, r.width, 3));
    return py::make_tuple(image, stats_dict(r.stats), components);
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
               const py::object& emission, float roughness) {
                ps::Material mat;
                mat.name = name;
                mat.kind = ps::material_kind_from_string(kind);
                mat.color = vec3(color, "material '" + name + "'.color");
                mat.ior = ior;
                mat.emission = vec3(emission, "material '" + name + "'.emission");
                mat.roughness = roughness;  // validated by the core: finite, in [0, 1]
                return s.add_material(mat);
            },
            "name"_a, "kind"_a = "diffuse", "color"_a = py::make_tuple(0.8, 0.8, 0.8), "ior"_a = 1.45f,
            "emission"_a = py::make_tuple(0.0, 0.0, 0.0), "roughness"_a = 0.5f,
            "Adds a material ('diffuse', 'mirror', 'glass' or 'glossy'); returns its index for material_ids. "
            "roughness (glossy only, Blender's, in [0, 1]): GGX with alpha = roughness^2; <= 0.05 is a mirror.")
        .def("add_mesh", &add_mesh, "name"_a, "vertices"_a, "triangles"_a, "normals"_a = py::none(),
             "material_ids"_a = py::none(), "transform"_a = py::none(),
             "Adds a triangle mesh: vertices (N,3), triangles (M,3), optional normals (N,3) or (M,3,3), "
             "material_ids (M,), transform (4,4) row-major object-to-world.")
        .def(
            "add_point_light",
            [](ps::Scene& s, const std::string& name, const py::object& position, const py::object& intensity,
               float radius) {
                ps::Light l;
                l.name = name;
                l.kind = ps::LightKind::point;
                l.position = vec3(position, "point light '" + name + "'.position");
                l.value = vec3(intensity, "point light '" + name + "'.intensity");
                l.radius = radius;
                s.add_light(l);
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
               const py::object& axis_v, const py::object& radiance) {
                ps::Light l;
                l.name = name;
                l.kind = ps::LightKind::area;
                l.position = vec3(center, "area light '" + name + "'.center");
                l.axis_u = vec3(axis_u, "area light '" + name + "'.axis_u");
                l.axis_v = vec3(axis_v, "area light '" + name + "'.axis_v");
                l.value = vec3(radiance, "area light '" + name + "'.radiance");
                s.add_light(l);
            },
            "name"_a, "center"_a, "axis_u"_a, "axis_v"_a, "radiance"_a,
            "One-sided rectangle with full edge vectors u, v, emitting radiance towards cross(u, v).")
        .def(
            "set_background", [](ps::Scene& s, const py::object& radiance) { s.set_background(vec3(radiance, "background")); },
            "radiance"_a)
        .def_property_readonly("triangle_count", [](const ps::Scene& s) { return s.triangles().size(); })
        .def_property_readonly("dropped_triangles", &ps::Scene::dropped_triangles,
                               "Degenerate (zero-area) triangles dropped on entry.")
        .def_property_readonly("material_count", [](const ps::Scene& s) { return s.materials().size(); })
        .def_property_readonly("light_count", [](const ps::Scene& s) { return s.lights().size(); });

    py::class_<ps::Camera>(m, "Camera", "Camera from a (4,4) camera-to-world matrix and an OpenGL-style projection.")
        .def(py::init([](const py::object& to_world, const py::object& projection, const py::object& width,
                         const py::object& height) {
                 return ps::Camera(mat4(to_world, "camera.to_world"), mat4(projection, "camera.projection"),
                                   positive_int(width, "camera.width"), positive_int(height, "camera.height"));
             }),
             "to_world"_a, "projection"_a, "width"_a, "height"_a)
        .def_property_readonly("width", &ps::Camera::width)
        .def_property_readonly("height", &ps::Camera::height)
        .def_property_readonly("orthographic", &ps::Camera::orthographic);

    py::class_<ps::RenderSettings>(m, "RenderSettings", "Settings of one render; validated on construction.")
        .def(py::init(&make_settings), "photons"_a = 200000, "radius"_a = 0.0f, "method"_a = "cluster_cone",
             "max_bounces"_a = 8, "seed"_a = 0, "threads"_a = 0, "direct_samples"_a = 4, "normal_tolerance"_a = 60.0f,
             "plane_distance"_a = 0.0f, "kernel"_a = "uniform", "directional_level"_a = -1,
             "memory_budget"_a = 0)
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
        .def("__repr__", [](const ps::RenderSettings& s) {
            std::ostringstream o;
            o << "RenderSettings(photons=" << s.photons << ", radius=" << s.radius << ", method='"
              << ps::to_string(s.method) << "', max_bounces=" << s.max_bounces << ", seed=" << s.seed
              << ", threads=" << s.threads << ", direct_samples=" << s.direct_samples << ", kernel='"
              << ps::to_string(s.kernel) << "', directional_level=" << s.directional_level
              << ", memory_budget=" << s.memory_budget << ")";
            return o.str();
        });

    m.def("render", &render, "scene"_a, "camera"_a, "settings"_a = ps::RenderSettings(), "progress"_a = py::none(),
          "passes"_a = false,
          "Renders one frame. Returns (image, stats): image float32 (H, W, 4) linear radiance, row 0 at the top; "
          "with passes=True also a dict of 'emission', 'direct', 'indirect' (H, W, 3). progress(stage, fraction) "
          "is called about 10× a second on the calling thread; returning True cancels (raises Cancelled).");

    m.def("default_memory_budget", &ps::default_memory_budget,
          "Bytes a render may hold when RenderSettings.memory_budget is 0: 3/4 of available memory.");

    bind_images(m);
}
