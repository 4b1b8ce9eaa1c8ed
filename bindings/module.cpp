// The Python face of the native core: numpy arrays and plain values in, numpy arrays and dicts out.
// Thin on purpose: validation of meaning lives in the core; here we only check that arrays have the shape
// and kind promised, and name the field when they do not.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>

#include "arrays.h"
#include "background.h"
#include "bindings.h"
#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/image.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"

namespace py = pybind11;
using namespace pybind11::literals;

using namespace ps_py;

namespace {

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
    m.attr("FILM_OUTPUTS") = py::tuple(py::cast(ps::film_output_names(ps::kAllFilmOutputs)));
    // Whether this module reads and writes image files (write_image, add_texture(path=...)): True in the build
    // against Debian's libraries, False in the Blender extension's, which has no OpenImageIO and gets pixels.
    m.attr("IMAGE_FILES") = ps::image_files_supported();

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
               float radius, bool sphere) {
                LightReader l(ps::LightKind::point, name);
                const glm::dvec3 p = l.position(position, "position");
                l.light.value = l.vector(intensity, "intensity");
                l.light.radius = radius;
                l.light.sphere = sphere;
                s.add_light(l.light, p);
            },
            "name"_a, "position"_a, "intensity"_a, "radius"_a = 0.0f, "sphere"_a = false,
            "Isotropic point light; intensity in W/sr. radius > 0 gives it a size, of radiance I/(pi radius^2): "
            "sphere=False lights as a disc of that radius facing each receiver (Cycles 3.4, and Cycles 4.x with "
            "Soft Falloff on); sphere=True as a true sphere (Cycles 4.x with Soft Falloff off), which gives more "
            "light than the disc near it (d not much larger than radius) and the same far away.")
        .def(
            "add_sun_light",
            [](ps::Scene& s, const std::string& name, const py::object& direction, const py::object& irradiance,
               float angle) {
                LightReader l(ps::LightKind::sun, name);
                l.light.direction = l.vector(direction, "direction");
                l.light.value = l.vector(irradiance, "irradiance");
                l.light.angle = angle;
                s.add_light(l.light);
            },
            "name"_a, "direction"_a, "irradiance"_a, "angle"_a = 0.0f,
            "Distant light travelling along direction; irradiance in W/m²; angle = full angular diameter.")
        .def(
            "add_area_light",
            [](ps::Scene& s, const std::string& name, const py::object& center, const py::object& axis_u,
               const py::object& axis_v, const py::object& radiance, const std::string& shape) {
                LightReader l(ps::LightKind::area, name);
                const glm::dvec3 c = l.position(center, "center");
                l.light.axis_u = l.vector(axis_u, "axis_u");
                l.light.axis_v = l.vector(axis_v, "axis_v");
                l.light.value = l.vector(radiance, "radiance");
                if (shape != "rectangle" && shape != "ellipse")
                    throw ps::InvalidInput(l.field("shape"), "must be 'rectangle' or 'ellipse', got '" + shape + "'");
                l.light.ellipse = shape == "ellipse";
                s.add_light(l.light, c);
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

    bind_settings(m);  // before render(), whose default settings it needs

    m.def("render", &render, "scene"_a, "camera"_a, "settings"_a = ps::RenderSettings(), "progress"_a = py::none(),
          "passes"_a = false,
          "Renders one frame. Returns (image, stats): image float32 (H, W, 4) linear radiance, row 0 at the top; "
          "with passes=True also a dict of the film outputs settings.outputs asks for beyond combined ('emission', "
          "'direct', 'indirect', 'normal' (H, W, 3), 'depth' (H, W, 1) by default) and, with "
          "settings.caustics_pass, 'caustics' (H, W, 3); without it only combined is made. progress(stage, "
          "fraction) is called about 10× a second on the calling thread; returning True cancels (raises "
          "Cancelled). settings.iterations != 1 or a time_limit render progressively (the mean of the "
          "iterations); a cancel after the first iteration returns the mean so far with "
          "stats['values']['cancelled'] = 1.");

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
