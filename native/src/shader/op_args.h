// One instruction's operands as the interpreter hands them to a node's implementation: its params, and its input
// and output registers resolved against the register file. Internal to the shader program sources.
#pragma once
#include <cstdint>
#include <cstring>

#include <glm/vec3.hpp>

#include "photonsplat/shader_program.h"

namespace ps {

struct OpArgs {
    const int32_t* params;
    const int32_t* in;   // register index of each input (vectors: the first of three)
    const int32_t* out;  // register index of each output, -1: discarded
    float* reg;

    int param(int i) const { return params[i]; }
    // A param that holds a float's bits (as Cycles packs a float into a node word).
    float param_float(int i) const {
        float value;
        std::memcpy(&value, &params[i], sizeof value);
        return value;
    }
    float f(int i) const { return reg[in[i]]; }
    glm::vec3 v(int i) const { return glm::vec3(reg[in[i]], reg[in[i] + 1], reg[in[i] + 2]); }
    void set(int o, float value) const {
        if (out[o] >= 0) reg[out[o]] = value;
    }
    void set(int o, const glm::vec3& value) const {
        if (out[o] >= 0) {
            reg[out[o]] = value.x;
            reg[out[o] + 1] = value.y;
            reg[out[o] + 2] = value.z;
        }
    }
};

class Scene;

// Each group of ops is implemented in its own file; each returns false for an op that is not its own. An invalid
// mode (a param out of range) gives zeros, never undefined behaviour.
bool run_shading_point_op(ShaderOp op, const OpArgs& a, const float* tables, const Scene& scene,
                          const ShaderGlobals& g);                          // shader/shading_point_ops.cpp
bool run_image_op(ShaderOp op, const OpArgs& a, const Scene& scene, const ShaderGlobals& g);  // shader/image_ops.cpp
bool run_texture_op(ShaderOp op, const OpArgs& a, const float* tables);    // nodes/texture_nodes.cpp
bool run_converter_op(ShaderOp op, const OpArgs& a, const float* tables);  // nodes/converter_nodes.cpp

}  // namespace ps
