// What the add-on's scene translation needs beyond the basic Scene: meshes in object space and instances of
// them (Embree instancing), textures for base colours, spot lights and round area lights.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "arrays.h"
#include "bindings.h"
#include "photonsplat/errors.h"
#include "photonsplat/scene.h"
#include "photonsplat/textures.h"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ps_py {

namespace {

// The numpy arrays of one mesh, kept alive while the core copies them.
struct MeshArrays {
    py::array_t<float, py::array::c_style> vertices, normals, uvs;
    py::array_t<int32_t, py::array::c_style> triangles, material_ids;
    std::vector<py::array_t<float, py::array::c_style>> attributes;
};

// attributes={id: (N, k) or (M, 3, k) floats} (ids from Scene.attribute_id) and texspace=(location, size).
void mesh_extras(ps::MeshInput& mesh, const py::object& attributes_obj, const py::object& texspace_obj,
                 MeshArrays& arrays) {
    const std::string where = "mesh '" + mesh.name + "'";
    if (!attributes_obj.is_none()) {
        if (!py::isinstance<py::dict>(attributes_obj))
            throw ps::InvalidInput(where + ".attributes", "must be a dict {attribute id: array}");
        const py::dict d = py::reinterpret_borrow<py::dict>(attributes_obj);
        arrays.attributes.reserve(d.size());
        for (const auto& [key, value] : d) {
            ps::MeshInput::Attribute a;
            const std::string field = where + ".attributes[" + std::string(py::str(key)) + "]";
            try {
                a.id = py::cast<uint32_t>(key);
            } catch (const py::cast_error&) {
                throw ps::InvalidInput(field, "keys must be attribute ids (Scene.attribute_id)");
            }
            arrays.attributes.push_back(float_array(py::reinterpret_borrow<py::object>(value), field));
            const auto& held = arrays.attributes.back();
            const auto m = static_cast<py::ssize_t>(mesh.triangle_count), n = static_cast<py::ssize_t>(mesh.vertex_count);
            a.per_corner = held.ndim() == 3;
            a.components = static_cast<int>(held.ndim() >= 2 ? held.shape(held.ndim() - 1) : 0);
            if (a.components < 1 || a.components > 4 || (a.per_corner && (held.shape(0) != m || held.shape(1) != 3)) ||
                (!a.per_corner && (held.ndim() != 2 || held.shape(0) != n)))
                throw ps::InvalidInput(field, "must be (N, k) per vertex or (M, 3, k) per corner, k in 1..4, got " +
                                                  shape_of(held));
            a.data = held.data();
            mesh.attributes.push_back(a);
        }
    }
    if (!texspace_obj.is_none()) {
        const auto t = float_array(texspace_obj, where + ".texspace");
        require_shape(t, {2, 3}, where + ".texspace", "(location, size), (2, 3)");
        mesh.has_texspace = true;
        mesh.texspace_location = glm::vec3(t.at(0, 0), t.at(0, 1), t.at(0, 2));
        mesh.texspace_size = glm::vec3(t.at(1, 0), t.at(1, 1), t.at(1, 2));
    }
}

// An optional attribute of `columns` floats per vertex, (N, columns), or per triangle corner, (M, 3, columns):
// nullptr for None, else its data, kept alive by `held`; `per_corner` is set to which of the two it is.
const float* per_vertex_or_corner(const py::object& obj, const std::string& field, py::ssize_t n, py::ssize_t m,
                                  py::ssize_t columns, py::array_t<float, py::array::c_style>& held,
                                  bool& per_corner) {
    if (obj.is_none()) return nullptr;
    held = float_array(obj, field);
    per_corner = held.ndim() == 3;
    const std::string c = std::to_string(columns);
    const std::string corner = "(M, 3, " + c + ") per corner", vertex = "(N, " + c + ") per vertex";
    if (per_corner)
        require_shape(held, {m, 3, columns}, field, corner + " or " + vertex);
    else
        require_shape(held, {n, columns}, field, vertex + " or " + corner);
    return held.data();
}

ps::MeshInput mesh_input(const std::string& name, const py::object& vertices_obj, const py::object& triangles_obj,
                         const py::object& normals_obj, const py::object& uvs_obj, const py::object& material_ids_obj,
                         MeshArrays& arrays) {
    const std::string where = "mesh '" + name + "'";
    arrays.vertices = float_array(vertices_obj, where + ".vertices");
    require_shape(arrays.vertices, {-1, 3}, where + ".vertices", "(N, 3)");
    arrays.triangles = index_array(triangles_obj, where + ".triangles");
    require_shape(arrays.triangles, {-1, 3}, where + ".triangles", "(M, 3)");
    ps::MeshInput mesh;
    mesh.name = name;
    mesh.vertices = arrays.vertices.data();
    mesh.vertex_count = static_cast<size_t>(arrays.vertices.shape(0));
    mesh.triangles = arrays.triangles.data();
    mesh.triangle_count = static_cast<size_t>(arrays.triangles.shape(0));
    const auto m = static_cast<py::ssize_t>(mesh.triangle_count), n = static_cast<py::ssize_t>(mesh.vertex_count);
    mesh.normals = per_vertex_or_corner(normals_obj, where + ".normals", n, m, 3, arrays.normals,
                                        mesh.normals_per_corner);
    mesh.uvs = per_vertex_or_corner(uvs_obj, where + ".uvs", n, m, 2, arrays.uvs, mesh.uvs_per_corner);
    if (!material_ids_obj.is_none()) {
        arrays.material_ids = index_array(material_ids_obj, where + ".material_ids");
        require_shape(arrays.material_ids, {m}, where + ".material_ids", "(M,)");
        mesh.material_ids = arrays.material_ids.data();
    }
    return mesh;
}

uint32_t visibility_bits(bool camera, bool shadow, bool indirect) {
    return (camera ? ps::kCameraRays : 0u) | (shadow ? ps::kShadowRays : 0u) | (indirect ? ps::kIndirectRays : 0u);
}

// A (H, W, C) float image -> Texture; rows in Blender's order (row 0 at the bottom).
ps::Texture texture_from_array(const std::string& name, const py::object& pixels_obj, const std::string& color_space,
                               bool premultiplied) {
    const std::string where = "texture '" + name + "'";
    auto pixels = float_array(pixels_obj, where + ".pixels");
    if (pixels.ndim() != 3)
        throw ps::InvalidInput(where + ".pixels", "must be (H, W, C) with C = 1, 3 or 4, got " + shape_of(pixels));
    return ps::Texture(name, pixels.data(), static_cast<int>(pixels.shape(1)), static_cast<int>(pixels.shape(0)),
                       static_cast<int>(pixels.shape(2)), ps::color_space_from_string(color_space), premultiplied);
}

}  // namespace

void bind_translation(py::module_& m) {
    auto scene = py::reinterpret_borrow<py::class_<ps::Scene>>(m.attr("Scene"));
    scene
        .def_property("build_bvhs_ahead", &ps::Scene::build_bvhs_ahead, &ps::Scene::set_build_bvhs_ahead,
                      "True: add_mesh_data starts building the mesh's BVH on a thread of the scene's own (the GIL "
                      "not needed) and returns, so that the caller prepares the next mesh meanwhile; the render "
                      "takes the BVHs built. The same BVHs and images either way. Default False: no thread.")
        .def_property(
            "multiscatter_light_estimate",
            [](const ps::Scene& s) {
                return std::string(s.multiscatter_light_estimate() == ps::MultiScatterEstimate::light_sample_as_walk
                                       ? "walk"
                                       : "light_sample");
            },
            [](ps::Scene& s, const std::string& name) {
                if (name != "walk" && name != "light_sample")
                    throw ps::InvalidInput("Scene.multiscatter_light_estimate",
                                           "must be 'light_sample' or 'walk', got '" + name + "'");
                s.set_multiscatter_light_estimate(name == "walk" ? ps::MultiScatterEstimate::light_sample_as_walk
                                                                 : ps::MultiScatterEstimate::light_sample);
            },
            "How light samples evaluate a Multiscatter GGX lobe: 'light_sample' (the default) as Cycles 3.x, whose "
            "evaluation towards a light tints each bounce after the first twice; 'walk' as its sampled directions "
            "(and Cycles 4.x) do, once.")
        .def_property(
            "bump_shadowing",
            [](const ps::Scene& s) { return std::string(s.cycles4_bump_shadowing() ? "cycles4" : "cycles3"); },
            [](ps::Scene& s, const std::string& name) {
                if (name != "cycles3" && name != "cycles4")
                    throw ps::InvalidInput("Scene.bump_shadowing", "must be 'cycles3' or 'cycles4', got '" + name + "'");
                s.set_cycles4_bump_shadowing(name == "cycles4");
            },
            "Which bump shadowing term diffuse closures under a bumped or tilted normal take: 'cycles3' (the "
            "default), Cycles 3.x's; 'cycles4', Cycles 4.x's, softened where a material's bump_map_correction is on.")
        .def(
            "add_mesh_data",
            [](ps::Scene& s, const std::string& name, const py::object& vertices, const py::object& triangles,
               const py::object& normals, const py::object& uvs, const py::object& material_ids,
               const py::object& attributes, const py::object& texspace) {
                MeshArrays arrays;
                ps::MeshInput mesh = mesh_input(name, vertices, triangles, normals, uvs, material_ids, arrays);
                mesh_extras(mesh, attributes, texspace, arrays);
                return s.add_mesh_data(mesh);
            },
            "name"_a, "vertices"_a, "triangles"_a, "normals"_a = py::none(), "uvs"_a = py::none(),
            "material_ids"_a = py::none(), "attributes"_a = py::none(), "texspace"_a = py::none(),
            "Adds a mesh in object space without placing it: vertices (N,3), triangles (M,3), optional normals "
            "(N,3) or (M,3,3), uvs (N,2) or (M,3,2), material_ids (M,), attributes {Scene.attribute_id(name): "
            "(N,k) or (M,3,k)} for shader programs, texspace ((location), (size)): Blender's texture space for "
            "Generated coordinates (default: the mesh's box). Returns the mesh id for add_instance.")
        .def(
            "add_instance",
            [](ps::Scene& s, uint32_t mesh, const py::object& transform, const std::string& name, bool camera,
               bool shadow, bool indirect, const py::object& object_info, float terminator_offset) {
                const uint32_t id = s.add_instance(mesh, dmat4(transform, "instance '" + name + "'.transform"), name,
                                                   visibility_bits(camera, shadow, indirect));
                if (terminator_offset != 0.0f) s.set_instance_terminator_offset(id, terminator_offset);
                if (!object_info.is_none()) {
                    const std::string where = "instance '" + name + "'.object_info";
                    if (!py::isinstance<py::dict>(object_info))
                        throw ps::InvalidInput(where, "must be a dict with color, pass_index, random");
                    const py::dict d = py::reinterpret_borrow<py::dict>(object_info);
                    glm::vec4 color(1.0f);
                    if (d.contains("color")) {
                        const auto c = float_array(d["color"], where + ".color");
                        require_shape(c, {4}, where + ".color", "(r, g, b, a)");
                        color = glm::vec4(c.at(0), c.at(1), c.at(2), c.at(3));
                    }
                    const float pass_index = d.contains("pass_index") ? py::cast<float>(d["pass_index"]) : 0.0f;
                    const float random = d.contains("random") ? py::cast<float>(d["random"]) : 0.0f;
                    s.set_instance_info(id, color, pass_index, random);
                }
                return id;
            },
            "mesh_id"_a, "transform"_a, "name"_a = "", "visible_camera"_a = true, "visible_shadow"_a = true,
            "visible_indirect"_a = true, "object_info"_a = py::none(), "terminator_offset"_a = 0.0f,
            "Places mesh mesh_id with a (4,4) row-major object-to-world transform (read in float64: a scene far "
            "from the origin keeps its precision); returns the instance id. "
            "visible_*: which rays see it (camera rays, shadow rays, every other ray). object_info: {color (r,g,b,a), "
            "pass_index, random} for Object Info nodes. terminator_offset: Cycles' shadow terminator Geometry "
            "Offset in [0, 1] (Blender's default is 0.1): shadow rays from smooth triangles towards lights near "
            "their horizon start on the smooth surface.")
        .def(
            "set_instance_transform",
            [](ps::Scene& s, uint32_t instance, const py::object& transform) {
                s.set_instance_transform(instance, dmat4(transform, "instance.transform"));
            },
            "instance_id"_a, "transform"_a,
            "Moves an instance. Meshes and their BVHs are kept; the next render refits the top-level BVH over the "
            "instances only (O(instances), no triangle touched). Call fit_origin() after the moves. Do not call "
            "during a render of this scene.")
        .def(
            "add_mesh",
            [](ps::Scene& s, const std::string& name, const py::object& vertices, const py::object& triangles,
               const py::object& normals, const py::object& material_ids, const py::object& transform,
               const py::object& uvs) {
                MeshArrays arrays;
                ps::MeshInput mesh = mesh_input(name, vertices, triangles, normals, uvs, material_ids, arrays);
                if (!transform.is_none()) mesh.transform = dmat4(transform, "mesh '" + name + "'.transform");
                s.add_mesh(mesh);
            },
            "name"_a, "vertices"_a, "triangles"_a, "normals"_a = py::none(), "material_ids"_a = py::none(),
            "transform"_a = py::none(), "uvs"_a = py::none(),
            "Adds a triangle mesh and one instance of it (add_mesh_data + add_instance): vertices (N,3), "
            "triangles (M,3), optional normals (N,3) or (M,3,3), material_ids (M,), transform (4,4) row-major "
            "object-to-world, uvs (N,2) or (M,3,2).")
        .def(
            "add_texture",
            [](ps::Scene& s, const std::string& name, const py::object& path, const py::object& pixels,
               const std::string& color_space, const std::string& alpha) {
                if (alpha != "straight" && alpha != "premultiplied")
                    throw ps::InvalidInput("texture '" + name + "'.alpha", "must be 'straight' or 'premultiplied'");
                const ps::ColorSpace space = ps::color_space_from_string(color_space);
                if (path.is_none() == pixels.is_none())
                    throw ps::InvalidInput("texture '" + name + "'", "give exactly one of path and pixels");
                if (!path.is_none()) {
                    const std::string file = py::str(path);
                    py::gil_scoped_release release;
                    return s.add_texture(ps::load_texture(name, file, space, "texture '" + name + "'.path"));
                }
                return s.add_texture(texture_from_array(name, pixels, color_space, alpha == "premultiplied"));
            },
            "name"_a, "path"_a = py::none(), "pixels"_a = py::none(), "color_space"_a = "sRGB", "alpha"_a = "straight",
            "Adds an image texture from a file (read with OpenImageIO; not where IMAGE_FILES is False) or from "
            "pixels (H,W,C) with row 0 at the bottom (Blender's Image.pixels); color_space 'sRGB' (decoded after "
            "interpolation, as Cycles does for 8-bit images) or 'linear'; alpha of pixels: 'straight' or "
            "'premultiplied' (Blender's float buffers); files say which themselves. Returns its index for add_material(texture=...).")
        .def(
            "add_spot_light",
            [](ps::Scene& s, const std::string& name, const py::object& position, const py::object& direction,
               const py::object& intensity, float spot_size, float spot_blend, float radius, bool sphere,
               bool spot_cosine, bool multiple_importance, bool cast_shadow) {
                LightReader l(ps::LightKind::spot, name);
                l.switches(multiple_importance, cast_shadow);
                const glm::dvec3 p = l.position(position, "position");
                l.light.direction = l.vector(direction, "direction");
                l.light.value = l.vector(intensity, "intensity");
                l.light.spot_size = spot_size;
                l.light.spot_blend = spot_blend;
                l.light.radius = radius;
                l.light.sphere = sphere;
                l.light.spot_cosine = spot_cosine;
                s.add_light(l.light, p);
            },
            "name"_a, "position"_a, "direction"_a, "intensity"_a, "spot_size"_a, "spot_blend"_a = 0.0f,
            "radius"_a = 0.0f, "sphere"_a = false, "spot_cosine"_a = true, "multiple_importance"_a = true,
            "cast_shadow"_a = true,
            "Spot light: intensity (W/sr) on its axis `direction`, full cone angle spot_size (radians), edge "
            "blend in [0, 1]. spot_cosine=True: Cycles 3.4's falloff cos θ · smoothstep; False: Cycles 4.x's "
            "smoothstep alone (no cos θ, so 1/cos θ brighter off the axis). radius and sphere as add_point_light's: "
            "sphere=False a disc facing the receiver (Cycles 3.4, and 4.x with Soft Falloff on), True a true "
            "sphere (Cycles 4.x with Soft Falloff off) whose cone attenuates each ray along its own direction."
            PS_LIGHT_SWITCHES_DOC)
        .def_property_readonly("mesh_count", [](const ps::Scene& s) { return s.meshes().size(); })
        .def_property_readonly("instance_count", [](const ps::Scene& s) { return s.instances().size(); })
        .def_property_readonly("texture_count", [](const ps::Scene& s) { return s.textures().size(); })
        .def_property_readonly("stored_triangle_count", &ps::Scene::stored_triangle_count,
                               "Triangles held in memory (each mesh once, however often it is instanced).")
        .def_property_readonly("scene_bytes", &ps::Scene::bytes,
                               "Bytes held by meshes, instances and textures (not the BVH).");
}

}  // namespace ps_py
