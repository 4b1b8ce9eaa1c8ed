// Conversions between numpy / Python values and the core's types, shared by every file of the module.
// Each names the field it converts, so a wrong shape or dtype is reported as "<field> must ...".
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/lights.h"
#include "photonsplat/render.h"
#include "photonsplat/stats.h"

namespace ps_py {

namespace py = pybind11;

std::string shape_of(const py::array& a);
std::string dtype_of(const py::array& a);

// Any real floating or integer array becomes float32; anything else (strings, objects, bools) is refused.
py::array_t<float, py::array::c_style> float_array(const py::object& obj, const std::string& field);

// Integer arrays only: a float index is almost always a bug in the caller's script.
py::array_t<int32_t, py::array::c_style> index_array(const py::object& obj, const std::string& field);

// Shape check; -1 in `shape` matches any extent. `expected` is how the message spells the shape.
void require_shape(const py::array& a, std::initializer_list<py::ssize_t> shape, const std::string& field,
                   const std::string& expected);

glm::vec3 vec3(const py::object& obj, const std::string& field);         // 3 finite components
// Positions and transforms are read in double, whatever the array's dtype: float64 keeps a point far from the
// world origin exact (the core subtracts the render origin before rounding to float, see scene.h).
glm::dvec3 dvec3(const py::object& obj, const std::string& field);       // 3 finite components
glm::dmat4 dmat4(const py::object& obj, const std::string& field);       // (4, 4) row-major numpy
glm::mat4 mat4(const py::object& obj, const std::string& field);         // (4, 4) row-major numpy, float
int positive_int(const py::object& obj, const std::string& field);       // Python int in [1, 65536]

// A light of one kind being filled from Python arguments: reads its fields with messages that name the light
// ("spot light 'Key'.direction must ...").
struct LightReader {
    ps::Light light;

    LightReader(ps::LightKind kind, const std::string& name);
    std::string field(const std::string& name) const;                       // "<kind> light '<light>'.<name>"
    glm::vec3 vector(const py::object& obj, const std::string& name) const;     // vec3 named field(name)
    glm::dvec3 position(const py::object& obj, const std::string& name) const;  // dvec3 named field(name)
    // Cycles' per-light switches every add_*_light takes (ps::Light::multiple_importance, cast_shadow).
    void switches(bool multiple_importance, bool cast_shadow) {
        light.multiple_importance = multiple_importance;
        light.cast_shadow = cast_shadow;
    }
};
// The keyword arguments' documentation every add_*_light ends with.
#define PS_LIGHT_SWITCHES_DOC                                                                                     \
    " multiple_importance=False: Cycles' Multiple Importance off, no ray but the camera's meets the light (it is " \
    "not seen in mirrors or glass, lights nothing through them) and its light samples take their full value; "     \
    "cast_shadow=False: Cycles' Cast Shadow off, its light samples take no shadow ray."


// (height, width, channels) float32 copy of a row-major buffer.
py::array_t<float> image_array(const std::vector<float>& data, int height, int width, int channels);

// The per-pass images of a render: 'emission', 'direct', 'indirect', 'normal' (H, W, 3), 'depth' (H, W, 1) and
// 'caustics' (H, W, 3) when the render computed it.
py::dict pass_images(const ps::RenderResult& r);

py::dict to_dict(const std::map<std::string, double>& m);
py::dict stats_dict(const ps::Stats& stats);  // {"seconds", "counters", "bytes", "values"}

}  // namespace ps_py
