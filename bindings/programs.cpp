// Shader programs (shader_program.h): the op table for the add-on's compiler, programs read from dicts, mesh
// attribute names and the per-instance values Object Info reads.
#include <cstring>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "photonsplat/errors.h"
#include "photonsplat/material_program.h"
#include "photonsplat/mesh_islands.h"
#include "photonsplat/scene.h"
#include "photonsplat/shader_program.h"

namespace py = pybind11;
using namespace pybind11::literals;

namespace ps_py {

namespace {

template <typename T>
std::vector<T> number_list(const py::handle& obj, const std::string& field) {
    std::vector<T> out;
    try {
        for (const py::handle& item : py::reinterpret_borrow<py::iterable>(obj)) out.push_back(py::cast<T>(item));
    } catch (const py::error_already_set&) {
        throw ps::InvalidInput(field, "must be a list of numbers");
    } catch (const py::cast_error&) {
        throw ps::InvalidInput(field, "must be a list of numbers");
    }
    return out;
}

}  // namespace

ps::ShaderProgram shader_program_from(const py::object& obj, const std::string& where) {
    ps::ShaderProgram p;
    if (obj.is_none()) return p;
    if (!py::isinstance<py::dict>(obj)) throw ps::InvalidInput(where, "must be a dict or None");
    const py::dict d = py::reinterpret_borrow<py::dict>(obj);
    for (const auto& [key, value] : d) {
        const std::string k = py::str(key);
        if (k != "code" && k != "registers" && k != "tables" && k != "outputs")
            throw ps::InvalidInput(where, "unknown key '" + k + "'");
    }
    if (d.contains("code")) p.code = number_list<int32_t>(d["code"], where + ".code");
    if (d.contains("registers")) p.registers = number_list<float>(d["registers"], where + ".registers");
    if (d.contains("tables")) p.tables = number_list<float>(d["tables"], where + ".tables");
    if (d.contains("outputs")) {
        size_t i = 0;
        for (const py::handle& item : py::reinterpret_borrow<py::iterable>(d["outputs"])) {
            const std::string at = where + ".outputs[" + std::to_string(i++) + "]";
            if (!py::isinstance<py::dict>(item)) throw ps::InvalidInput(at, "must be a dict");
            const py::dict o = py::reinterpret_borrow<py::dict>(item);
            ps::ProgramOutput out;
            if (!o.contains("target") || !o.contains("register"))
                throw ps::InvalidInput(at, "needs 'target' and 'register'");
            try {
                out.target = ps::program_target_from_string(py::cast<std::string>(o["target"]));
                out.register_ = py::cast<int32_t>(o["register"]);
                if (o.contains("index")) out.index = py::cast<int32_t>(o["index"]);
            } catch (const py::cast_error&) {
                throw ps::InvalidInput(at, "target must be a string, register and index integers");
            }
            p.outputs.push_back(out);
        }
    }
    return p;
}

void bind_programs(py::module_& m) {
    m.def(
        "shader_ops",
        []() {
            py::list ops;
            for (int i = 0; i < ps::shader_op_count(); ++i) {
                const ps::ShaderOpInfo& info = ps::shader_op_info(static_cast<ps::ShaderOp>(i));
                ops.append(py::dict("name"_a = info.name, "id"_a = i, "params"_a = info.params,
                                    "inputs"_a = info.inputs, "outputs"_a = info.outputs));
            }
            return ops;
        },
        "The shader program ops (native/include/photonsplat/shader_program.h): a list of dicts with name, id, "
        "params (count), inputs and outputs (type strings: 'f' float, 'v' vector of three registers).");
    m.def(
        "program_timing",
        [](bool reset) {
            const ps::ProgramTiming t = ps::program_timing(reset);
            return py::dict("runs"_a = t.runs, "seconds"_a = t.seconds);
        },
        "reset"_a = true,
        "Runs of material programs and their time summed over threads since the last reset; measured only when "
        "the process started with PHOTONSPLAT_PROGRAM_TIMING set (tools/benchmark.py --program-timing).");
    m.def(
        "random_per_island",
        [](size_t num_vertices, const py::object& edges_obj) {
            const auto edges = index_array(edges_obj, "edges");
            if (edges.size() != 0 && (edges.ndim() != 2 || edges.shape(1) != 2))
                throw ps::InvalidInput("edges", "must be (E, 2) vertex indices");
            const size_t count = edges.size() / 2;
            std::vector<float> values;
            {
                py::gil_scoped_release release;
                values = ps::random_per_island(num_vertices, edges.data(), count);
            }
            py::array_t<float> out(static_cast<py::ssize_t>(values.size()));
            if (!values.empty()) std::memcpy(out.mutable_data(), values.data(), values.size() * sizeof(float));
            return out;
        },
        "num_vertices"_a, "edges"_a,
        "Cycles' Random Per Island of each vertex (float32 (N,)): hash_uint_to_float of the root of its island in "
        "a disjoint set joined along `edges` ((E, 2) int32, Blender's edge order), as Cycles 3.4's Blender sync.");
    auto scene = py::reinterpret_borrow<py::class_<ps::Scene>>(m.attr("Scene"));
    scene
        .def("attribute_id", &ps::Scene::attribute_id, "name"_a,
             "The id of a mesh attribute name (a UV map or colour attribute) for add_mesh_data(attributes=...) "
             "and the programs' uv_map / attribute / normal_map params; registered on first use.")
        .def(
            "set_instance_info",
            [](ps::Scene& s, uint32_t instance, const py::object& color, float pass_index, float random) {
                const auto c = float_array(color, "instance.object_info.color");
                if (c.ndim() != 1 || c.shape(0) != 4)
                    throw ps::InvalidInput("instance.object_info.color", "must be (r, g, b, a)");
                s.set_instance_info(instance, glm::vec4(c.at(0), c.at(1), c.at(2), c.at(3)), pass_index, random);
            },
            "instance_id"_a, "color"_a = py::make_tuple(1.0, 1.0, 1.0, 1.0), "pass_index"_a = 0.0f,
            "random"_a = 0.0f, "What Object Info nodes read of an instance: its colour, pass index and random number.");
}

}  // namespace ps_py
