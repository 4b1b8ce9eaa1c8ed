// The world: its node program, its portals, and the world as a light for tests (world.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "photonsplat/errors.h"
#include "photonsplat/scene.h"
#include "photonsplat/shader_program.h"
#include "photonsplat/world.h"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ps_py {

void bind_world(py::module_& m) {
    auto scene = py::reinterpret_borrow<py::class_<ps::Scene>>(m.attr("Scene"));
    scene.def(
        "set_world_program",
        [](ps::Scene& s, const py::object& program, int map_resolution) {
            if (program.is_none()) {
                s.clear_world_program();
                return;
            }
            s.set_world_program(shader_program_from(program, "world.program"), map_resolution);
        },
        "program"_a, "map_resolution"_a = 0,
        "The world as a node program evaluated per direction (a program dict as add_material's, with only an "
        "'emission' output: the radiance; P = the direction, N = I = -direction). None: back to set_background's "
        "constant. A program that folds to a constant becomes that constant. map_resolution: width of the "
        "importance map (height half of it), 0 = automatic (the widest Environment Texture, else 1024).");
    scene.def_property_readonly(
        "world_programmed", [](const ps::Scene& s) { return s.world_program() != nullptr; },
        "Whether the world is a node program (False: the constant background).");
    scene.def(
        "add_portal",
        [](ps::Scene& s, const std::string& name, const py::object& corner, const py::object& edge_u,
           const py::object& edge_v) {
            ps::Portal p;
            p.name = name;
            const std::string where = "portal '" + name + "'";
            p.corner = dvec3(corner, where + ".corner");
            p.edge_u = vec3(edge_u, where + ".edge_u");
            p.edge_v = vec3(edge_v, where + ".edge_v");
            s.add_portal(p);
        },
        "name"_a, "corner"_a, "edge_u"_a, "edge_v"_a,
        "A rectangle corner + s*edge_u + t*edge_v (s, t in [0, 1]) the world lights the scene through (Cycles' "
        "portal lights): light passes it travelling along cross(edge_u, edge_v). clear_lights() removes portals.");
    scene.def_property_readonly("portal_count", [](const ps::Scene& s) { return s.portals().size(); });
    scene.def(
        "world_radiance",
        [](const ps::Scene& s, const py::object& direction, bool camera) {
            const glm::vec3 d = glm::normalize(vec3(direction, "direction"));
            const glm::vec3 r = ps::world_radiance(s, d, camera ? ps::ShaderRay::camera : ps::ShaderRay::shadow);
            return py::make_tuple(r.x, r.y, r.z);
        },
        "direction"_a, "camera"_a = false,
        "The world's radiance seen by a ray travelling along `direction` (a camera ray, or a light sample's "
        "evaluation).");
    scene.def(
        "world_map_info",
        [](const ps::Scene& s) {
            const auto light = s.world_light();
            py::dict d;
            const glm::vec3 i = light->radiance_integral();
            d["constant"] = light->constant();
            d["black"] = light->black();
            d["radiance_integral"] = py::make_tuple(i.x, i.y, i.z);
            d["map_width"] = light->map() ? light->map()->width() : 0;
            d["map_height"] = light->map() ? light->map()->height() : 0;
            return d;
        },
        "The world as a light, as the renderer builds it: whether it is constant, black, its map's size and "
        "∫ L dω (RGB).");
}

}  // namespace ps_py
