// In-place changes to a Scene that already holds meshes, for the viewport's incremental updates: a moved light
// replaces the lights without touching meshes or the BVH; after moved instances the render origin follows them.
// (Moving instances is set_instance_transform, in translation.cpp next to add_instance.)
#include <pybind11/pybind11.h>

#include "arrays.h"
#include "bindings.h"
#include "photonsplat/scene.h"

namespace ps_py {

void bind_scene_updates(py::module_& m) {
    auto scene = py::reinterpret_borrow<py::class_<ps::Scene>>(m.attr("Scene"));
    scene.def("clear_lights", &ps::Scene::clear_lights,
              "Removes every light (meshes, instances, materials, textures, background and the BVH stay), so "
              "that the lights can be added again after a change. Do not call during a render of this scene.");
    scene.def_property_readonly(
        "origin", [](const ps::Scene& s) { return py::make_tuple(s.origin().x, s.origin().y, s.origin().z); },
        "The world point the core's float coordinates are relative to (render space = world - origin).");
    scene.def("fit_origin", &ps::Scene::fit_origin,
              "After set_instance_transform calls: moves the render origin (the point the core's float coordinates "
              "are relative to) to where the instances now are, O(instances), so that objects moved far from the "
              "world origin keep their precision; the scene then renders as one built anew. Do not call during a "
              "render of this scene.");
}

}  // namespace ps_py
