// The module is split by area; module.cpp calls each bind_* in turn. A new area (reference renderer, metrics,
// progressive rendering, ...) gets its own bindings/<area>.cpp and one line here and in module.cpp.
#pragma once
#include <string>

#include <pybind11/pybind11.h>

namespace ps_py {

void bind_settings(pybind11::module_& m);     // settings.cpp: RenderSettings and SETTINGS, from the settings table
void bind_images(pybind11::module_& m);       // images.cpp: write_image
void bind_metrics(pybind11::module_& m);      // metrics.cpp: psnr, ssim, rmse, relmse
void bind_reference(pybind11::module_& m);    // reference.cpp: render_reference
void bind_translation(pybind11::module_& m);  // translation.cpp: meshes + instances, textures, spot lights
void bind_progressive(pybind11::module_& m);  // progressive.cpp: Progressive (stepping, for the viewport)
void bind_scene_updates(pybind11::module_& m);
void bind_world(pybind11::module_& m);        // world.cpp: Scene.set_world_program, add_portal, world_radiance
void bind_programs(pybind11::module_& m);     // programs.cpp: shader_ops, Scene.attribute_id / set_instance_info  // scene_updates.cpp: Scene.clear_lights (viewport updates)

}  // namespace ps_py

namespace ps {
struct ShaderProgram;
}
namespace ps_py {
// A program dict {"code", "registers", "tables", "outputs"} (programs.cpp); None: an empty program.
ps::ShaderProgram shader_program_from(const pybind11::object& obj, const std::string& where);
}  // namespace ps_py
