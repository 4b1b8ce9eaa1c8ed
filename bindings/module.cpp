// The Python face of the native core: numpy arrays and plain values in, numpy arrays and dicts out.
// Thin on purpose: validation of meaning lives in the core; here we only check that arrays have the shape
// and kind promised, and name the field when they do not.
#include <algorithm>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>
#include <vector>

#include "arrays.h"
#include "background.h"
#include "bindings.h"
#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/image.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/ray_floor.h"
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

namespace {

// A dict's value for `key`, or nullptr when absent.
py::handle dict_item(const py::dict& d, const char* key) {
    return d.contains(key) ? py::handle(d[key]) : py::handle();
}

// One of the core's names (closure kind, distribution...), the error naming the whole field it came from.
template <typename Parse>
auto named(Parse parse, const py::handle& value, const std::string& field) {
    try {
        return parse(py::cast<std::string>(value));
    } catch (const ps::InvalidInput& e) {
        const std::string message = e.what();
        const size_t colon = message.find(": ");
        throw ps::InvalidInput(field, colon == std::string::npos ? message : message.substr(colon + 2));
    }
}

uint32_t factor_bits(const py::handle& indices, const std::string& field) {
    uint32_t bits = 0;
    for (const py::handle& item : py::iterable(py::reinterpret_borrow<py::object>(indices))) {
        const long j = py::cast<long>(item);
        if (j < 0 || j >= ps::kMaxFactors)
            throw ps::InvalidInput(field, "factor indices must be in [0, " + std::to_string(ps::kMaxFactors) + ")");
        bits |= 1u << j;
    }
    return bits;
}

// A list of dicts (closures, factors): each item checked to be a dict, its keys against `keys` when given, then
// read by `read(dict, where)`; errors name the item, e.g. "material 'm'.closures[2]".
template <typename T, typename Read>
std::vector<T> dict_list(const py::object& obj, const std::string& field, const std::vector<std::string>& keys,
                         Read read) {
    std::vector<T> out;
    if (obj.is_none()) return out;
    size_t i = 0;
    for (const py::handle& item : py::iterable(obj)) {
        const std::string where = field + "[" + std::to_string(i++) + "]";
        if (!py::isinstance<py::dict>(item)) throw ps::InvalidInput(where, "must be a dict");
        const py::dict d = py::reinterpret_borrow<py::dict>(item);
        for (const auto& [key, value] : d) {
            const std::string k = py::str(key);
            if (!keys.empty() && std::find(keys.begin(), keys.end(), k) == keys.end())
                throw ps::InvalidInput(where, "unknown key '" + k + "'");
        }
        out.push_back(read(d, where));
    }
    return out;
}

std::vector<ps::Closure> closure_list(const py::object& obj, const std::string& field) {
    static const std::vector<std::string> kKeys = {"kind", "distribution", "fresnel", "color", "specular_color",
                                                   "roughness", "alpha_x", "alpha_y", "ior", "reported_alpha",
                                                   "texture", "texture_target", "factors_on", "factors_off"};
    return dict_list<ps::Closure>(obj, field, kKeys, [](const py::dict& d, const std::string& where) {
        ps::Closure c;
        if (auto v = dict_item(d, "kind")) c.kind = named(ps::closure_kind_from_string, v, where + ".kind");
        else throw ps::InvalidInput(where + ".kind", "is required");
        if (auto v = dict_item(d, "distribution"))
            c.distribution = named(ps::distribution_from_string, v, where + ".distribution");
        if (auto v = dict_item(d, "fresnel")) c.fresnel = named(ps::fresnel_kind_from_string, v, where + ".fresnel");
        if (auto v = dict_item(d, "color")) c.color = vec3(py::reinterpret_borrow<py::object>(v), where + ".color");
        if (auto v = dict_item(d, "specular_color"))
            c.specular_color = vec3(py::reinterpret_borrow<py::object>(v), where + ".specular_color");
        if (auto v = dict_item(d, "roughness")) c.roughness = py::cast<float>(v);
        if (auto v = dict_item(d, "alpha_x")) c.alpha_x = py::cast<float>(v);
        if (auto v = dict_item(d, "alpha_y")) c.alpha_y = py::cast<float>(v);
        if (auto v = dict_item(d, "ior")) c.ior = py::cast<float>(v);
        if (auto v = dict_item(d, "reported_alpha")) c.reported_alpha = py::cast<float>(v);
        if (auto v = dict_item(d, "texture")) c.texture = py::cast<int32_t>(v);
        if (auto v = dict_item(d, "texture_target"))
            c.texture_target = named(ps::texture_target_from_string, v, where + ".texture_target");
        if (auto v = dict_item(d, "factors_on")) c.factors_on = factor_bits(v, where + ".factors_on");
        if (auto v = dict_item(d, "factors_off")) c.factors_off = factor_bits(v, where + ".factors_off");
        return c;
    });
}

std::vector<ps::MixFactor> factor_list(const py::object& obj, const std::string& field) {
    return dict_list<ps::MixFactor>(obj, field, {}, [](const py::dict& d, const std::string& where) {
        ps::MixFactor f;
        if (auto v = dict_item(d, "kind")) f.kind = named(ps::factor_kind_from_string, v, where + ".kind");
        else throw ps::InvalidInput(where + ".kind", "is required");
        if (auto v = dict_item(d, "value")) f.value = py::cast<float>(v);
        return f;
    });
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
               const py::object& emission, float roughness, int texture, bool holdout, const py::object& closures,
               const py::object& factors, const py::object& program, bool bump_map_correction) {
                ps::Material mat;
                mat.name = name;
                mat.kind = ps::material_kind_from_string(kind);
                const std::string where = "material '" + name + "'";
                mat.color = vec3(color, where + ".color");
                mat.ior = ior;
                mat.emission = vec3(emission, where + ".emission");
                mat.roughness = roughness;  // validated by the core: finite, in [0, 1]
                mat.texture = texture;      // validated by the scene: -1 or an existing texture
                mat.holdout = holdout;
                mat.bump_map_correction = bump_map_correction;
                if (mat.kind == ps::MaterialKind::closures) {
                    mat.closures = closure_list(closures, where + ".closures");
                    mat.factors = factor_list(factors, where + ".factors");
                    mat.program = shader_program_from(program, where + ".program");
                } else if (!closures.is_none() || !factors.is_none() || !program.is_none()) {
                    throw ps::InvalidInput(where + ".closures", "closures, factors and program need kind='closures'");
                }
                return s.add_material(mat);
            },
            "name"_a, "kind"_a = "diffuse", "color"_a = py::make_tuple(0.8, 0.8, 0.8), "ior"_a = 1.45f,
            "emission"_a = py::make_tuple(0.0, 0.0, 0.0), "roughness"_a = 0.5f, "texture"_a = -1, "holdout"_a = false,
            "closures"_a = py::none(), "factors"_a = py::none(), "program"_a = py::none(),
            "bump_map_correction"_a = true,
            "Adds a material; returns its index for material_ids. kind 'diffuse', 'mirror', 'glass' or 'glossy' is a "
            "simple material from color, ior, roughness (glossy only, Blender's, in [0, 1]: GGX with alpha = "
            "roughness^2; <= 0.05 is a mirror) and texture (index of add_texture() whose colour at the hit's UV "
            "replaces color, -1: none). kind 'closures' takes `closures`, a list of dicts (kind: diffuse, "
            "principled_diffuse, translucent, reflection, refraction, transparent, sheen, velvet; distribution: sharp, "
            "ggx, beckmann, multi_ggx, gtr1, multi_ggx_glass (one side of a Multiscatter GGX Glass); fresnel: none, "
            "principled, dielectric, schlick; color (the weight), specular_color, roughness, alpha_x, alpha_y, ior, "
            "reported_alpha (a sharp reflection Cycles 3.x renders as Multiscatter GGX of that alpha: "
            "Closure::reported_alpha), texture, texture_target ('color' or "
            "'specular_color'), factors_on and factors_off: indices into `factors`), and `factors`, a list of dicts "
            "(kind: fresnel, layer_fresnel, layer_facing; value: the IOR or Blend) whose value at each hit "
            "multiplies a closure's weight (factors_on) or 1 - it (factors_off). program: a shader program dict "
            "(shader_program.h; code, registers, tables, outputs with target, index, register) that sets closure "
            "inputs, the emission and the normal at each hit. emission: radiance W/(sr m^2) "
            "from both faces. holdout: cut out of the image where the camera sees it (alpha 0), black for other rays. "
            "bump_map_correction: Blender 4.x's material setting, which softens Cycles 4.x's bump shadowing term "
            "(Scene.bump_shadowing).")
        .def(
            "add_point_light",
            [](ps::Scene& s, const std::string& name, const py::object& position, const py::object& intensity,
               float radius, bool sphere, bool multiple_importance, bool cast_shadow) {
                LightReader l(ps::LightKind::point, name);
                l.switches(multiple_importance, cast_shadow);
                const glm::dvec3 p = l.position(position, "position");
                l.light.value = l.vector(intensity, "intensity");
                l.light.radius = radius;
                l.light.sphere = sphere;
                s.add_light(l.light, p);
            },
            "name"_a, "position"_a, "intensity"_a, "radius"_a = 0.0f, "sphere"_a = false,
            "multiple_importance"_a = true, "cast_shadow"_a = true,
            "Isotropic point light; intensity in W/sr. radius > 0 gives it a size, of radiance I/(pi radius^2): "
            "sphere=False lights as a disc of that radius facing each receiver (Cycles 3.4, and Cycles 4.x with "
            "Soft Falloff on); sphere=True as a true sphere (Cycles 4.x with Soft Falloff off), which gives more "
            "light than the disc near it (d not much larger than radius) and the same far away." PS_LIGHT_SWITCHES_DOC)
        .def(
            "add_sun_light",
            [](ps::Scene& s, const std::string& name, const py::object& direction, const py::object& irradiance,
               float angle, bool multiple_importance, bool cast_shadow) {
                LightReader l(ps::LightKind::sun, name);
                l.switches(multiple_importance, cast_shadow);
                l.light.direction = l.vector(direction, "direction");
                l.light.value = l.vector(irradiance, "irradiance");
                l.light.angle = angle;
                s.add_light(l.light);
            },
            "name"_a, "direction"_a, "irradiance"_a, "angle"_a = 0.0f, "multiple_importance"_a = true,
            "cast_shadow"_a = true,
            "Distant light travelling along direction; irradiance in W/m²; angle = full angular diameter." PS_LIGHT_SWITCHES_DOC)
        .def(
            "add_area_light",
            [](ps::Scene& s, const std::string& name, const py::object& center, const py::object& axis_u,
               const py::object& axis_v, const py::object& radiance, const std::string& shape,
               bool multiple_importance, bool cast_shadow) {
                LightReader l(ps::LightKind::area, name);
                l.switches(multiple_importance, cast_shadow);
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
            "multiple_importance"_a = true, "cast_shadow"_a = true,
            "One-sided rectangle with full edge vectors u, v (or, shape='ellipse', the ellipse inscribed in it), "
            "emitting radiance towards cross(u, v)." PS_LIGHT_SWITCHES_DOC)
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
          "fraction) is called about 40× a second on the calling thread; returning True cancels (raises "
          "Cancelled). settings.iterations != 1 or a time_limit render progressively (the mean of the "
          "iterations); a cancel after the first iteration returns the mean so far with "
          "stats['values']['cancelled'] = 1.");

    m.def(
        "ray_floor",
        [](const ps::Scene& scene, const ps::Camera& camera) {
            ps::RayFloor floor;
            {
                py::gil_scoped_release release;
                floor = ps::measure_ray_floor(scene, camera);
            }
            py::dict out;
            out["rays"] = floor.rays;
            out["seconds"] = floor.seconds;
            out["hits"] = floor.hits;
            out["rays_per_second"] = floor.seconds > 0.0 ? double(floor.rays) / floor.seconds : 0.0;
            return out;
        },
        "scene"_a, "camera"_a,
        "Embree's floor for this frame: its primary rays (one per pixel centre) traced as coherent 4 x 2 packets, "
        "nothing shaded. Returns {'rays', 'seconds', 'hits', 'rays_per_second'}; a render's stats['counters'] "
        "holds each stage's 'rays.<stage>' to compare with it. Builds the BVH first if needed, outside the time.");

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
    bind_programs(m);
    bind_world(m);
}
