// Shader programs: a material's node graph, compiled by the add-on (export/shader_program.py) into a flat list
// of node operations over a float register file, and interpreted by the core at each hit, as Cycles' SVM
// interprets the program its Blender sync compiles. The program computes the closure inputs, the emission and
// the shading normal that the node graph drives; the closures themselves stay Material::closures (closures.h).
//
// Encoding. `code` is a flat int32 array; each instruction is
//     op, n_params, n_inputs, n_outputs, params[n_params], inputs[n_inputs], outputs[n_outputs]
// with the counts fixed per op by the table below. Inputs and outputs are register indices: a float operand is
// one register, a vector or colour operand ("v") names the first of three consecutive registers. An output
// register of -1 is discarded (an unused socket). Registers start with `registers` (the constants and the
// unconnected socket values); `tables` holds baked colour ramps, curves and matrices, addressed by params.
//
// Op table: PS_SHADER_OPS(X) lists X(name, params, inputs, outputs), with inputs and outputs as type strings
// ("f" float, "v" vector/colour), in Blender 3.4's socket order. Params are integer modes, in the order of
// Cycles' own enums (svm/types.h) unless the comment says otherwise. The add-on reads this table through the
// module (photonsplat.shader_ops()), so it is the one definition of the encoding.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace ps {

// clang-format off
#define PS_SHADER_OPS(X)                                                                                           \
    /* --- moves and conversions (shader_program.cpp) --- */                                                     \
    X(copy_float,        0, "f",      "f")                                                                         \
    X(copy_vector,       0, "v",      "v")                                                                         \
    X(combine_xyz,       0, "fff",    "v")                                                                         \
    X(color_to_float,    0, "v",      "f")   /* Cycles' colour → float: luminance, nodes/color_math.h */        \
    X(vector_to_float,   0, "v",      "f")   /* vector → float: the average of the three */                        \
    X(float_to_vector,   0, "f",      "v")   /* broadcast */                                                       \
    /* --- the shading point (shader_globals_ops.cpp) --- */                                                      \
    /* params: bump (0 centre, 1 dx, 2 dy: the point offset for a Bump node's height), object matrix (tables   */ \
    /* offset of a 16-float column-major world → object matrix, -1: the hit object's own), the Bump node's     */ \
    /* filter width (a float's bits: the offset is width × dPdx or dPdy; 1 in Blender 3.x, its input in 4.x)   */ \
    X(texture_coordinate, 3, "",      "vvvvvvv") /* generated, normal, uv, object, camera, window, reflection */  \
    X(uv_map,            3, "",       "v")   /* params: bump, attribute id (-1: the render UV map), width */       \
    X(attribute,         3, "",       "vvff") /* params: bump, attribute id, width; color, vector, fac, alpha */   \
    X(geometry,          4, "",       "vvvvvvfff") /* params: bump, pointiness attribute id, random per island */ \
                                                   /* attribute id (-1: absent, 0 as Cycles' missing attribute),*/ \
                                                   /* width;                                                    */ \
                                                   /* position, normal, tangent, true normal, incoming,         */ \
                                                   /* parametric, backfacing, pointiness, random per island     */ \
    X(object_info,       0, "",       "vvffff") /* location, color, alpha, object index, material index (always */ \
                                              /* 0: the compiler substitutes the material's constant), random */  \
    X(light_path,        0, "",       "fffffffffffff") /* camera, shadow, diffuse, glossy, singular, reflection, */ \
                                     /* transmission, ray length, ray depth, diffuse, glossy, transparent,       */ \
                                     /* transmission depth */                                                      \
    X(camera_data,       0, "",       "vff") /* view vector, view z depth, view distance */                       \
    X(fresnel,           0, "fv",     "f")   /* ior, normal */                                                     \
    X(layer_weight,      0, "fv",     "ff")  /* blend, normal; fresnel, facing */                                  \
    /* params: texture (Scene::textures index), interpolation (0 linear, 1 closest, 2 cubic, 3 smart), extension */ \
    /* (0 repeat, 1 extend, 2 clip, 3 mirror), projection (0 flat, 1 box, 2 sphere, 3 tube), alpha (0 straight */ \
    /* colour: Cycles' unassociated output, 1 associated colour × alpha, 2 the stored colour: channel packed   */ \
    /* or alpha ignored) */                                                                                       \
    X(image_texture,     5, "vf",     "vf")  /* vector, box blend; color, alpha */                                 \
    X(environment_texture, 3, "v",    "vf")  /* params: texture, interpolation, projection (0 equirect, 1 mirror */ \
                                             /* ball); vector; color, alpha */                                     \
    X(normal_map,        3, "fv",     "v")   /* params: space (0 tangent, 1 object, 2 world, 3 blender object,   */ \
                                             /* 4 blender world), uv attribute id, tangent attribute id (per    */ \
                                             /* corner: MikkTSpace tangent xyz, bitangent sign w; -1: the       */ \
                                             /* triangle's UV tangent); strength, color; normal */                 \
    X(bump,              3, "fffffv", "v")   /* params: invert, normal connected, filter width (a float's bits); */ \
                                             /* strength, distance, height,                                     */ \
                                             /* height at dx, height at dy, normal; normal */                      \
    X(normal,            0, "vv",     "vf")  /* the node's direction, the input normal; normal, dot */             \
    X(vector_transform,  3, "v",      "v")   /* params: type (0 vector, 1 point, 2 normal), from, to (0 world,   */ \
                                             /* 1 object, 2 camera) */                                             \
    /* --- textures (nodes/texture_nodes.cpp) --- */                                                              \
    X(noise_texture,     1, "vfffff", "fv")  /* params: dimensions 1-4; vector, w, scale, detail, roughness,     */ \
                                             /* distortion; fac, color */                                          \
    X(voronoi_texture,   3, "vfffff", "fvvff") /* params: dimensions, feature (0 f1, 1 f2, 2 smooth f1,         */ \
                                             /* 3 distance to edge, 4 n-sphere radius), metric (0 euclidean,     */ \
                                             /* 1 manhattan, 2 chebychev, 3 minkowski); vector, w, scale,         */ \
                                             /* smoothness, exponent, randomness; distance, color, position, w,   */ \
                                             /* radius */                                                          \
    X(musgrave_texture,  2, "vfffffff", "f") /* params: dimensions, type (0 multifractal, 1 fBM, 2 hybrid,      */ \
                                             /* 3 ridged, 4 hetero terrain); vector, w, scale, detail, dimension, */ \
                                             /* lacunarity, offset, gain; fac */                                   \
    X(wave_texture,      4, "vffffff", "vf") /* params: type (0 bands, 1 rings), bands direction (0 x, 1 y, 2 z,  */ \
                                             /* 3 diagonal), rings direction (0 x, 1 y, 2 z, 3 spherical),        */ \
                                             /* profile (0 sine, 1 saw, 2 triangle); vector, scale, distortion,   */ \
                                             /* detail, detail scale, detail roughness, phase offset; color, fac  */ \
    X(magic_texture,     1, "vff",    "vf")  /* params: depth; vector, scale, distortion; color, fac */             \
    X(brick_texture,     2, "vvvvffffffff", "vf") /* params: offset frequency, squash frequency; vector, color1,  */ \
                                             /* color2, mortar, scale, mortar size, mortar smooth, bias, brick    */ \
                                             /* width, row height, offset, squash; color, fac */                   \
    X(checker_texture,   0, "vvvf",   "vf")  /* vector, color1, color2, scale; color, fac */                      \
    X(gradient_texture,  1, "v",      "vf")  /* params: type (0 linear, 1 quadratic, 2 easing, 3 diagonal,        */ \
                                             /* 4 spherical, 5 quadratic sphere, 6 radial); vector; color, fac */  \
    X(white_noise_texture, 1, "vf",   "fv")  /* params: dimensions; vector, w; value, color */                     \
    /* --- converters (nodes/converter_nodes.cpp) --- */                                                          \
    X(math,              2, "fff",    "f")   /* params: operation (NodeMathType), clamp */                         \
    X(vector_math,       1, "vvvf",   "vf")  /* params: operation (NodeVectorMathType); a, b, c, scale */          \
    X(map_range,         2, "ffffff", "f")   /* params: interpolation (0 linear, 1 stepped, 2 smoothstep,        */ \
                                             /* 3 smootherstep), clamp; value, from min, from max, to min, to max, */ \
                                             /* steps */                                                            \
    X(map_range_vector,  2, "vvvvvv", "v")   /* the same per component */                                          \
    X(clamp,             1, "fff",    "f")   /* params: type (0 min max, 1 range); value, min, max */              \
    X(color_ramp,        3, "f",      "vf")  /* params: table offset, entries, interpolate (0 constant,         */ \
                                             /* 1 linear); table: entries × rgba over fac 0..1 (Blender's baked  */ \
                                             /* ramp, as Cycles bakes it); color, alpha */                        \
    X(rgb_curves,        2, "fv",     "v")   /* params: table offset, entries; table: min x, max x, then entries */ \
                                             /* × rgb (each channel's curve composed with the combined curve),   */ \
                                             /* extrapolated linearly beyond the range; fac, color */              \
    X(vector_curves,     2, "fv",     "v")   /* the same table layout, per axis; fac, vector */                    \
    X(float_curve,       2, "ff",     "f")   /* params: table offset, entries; table: min x, max x, entries;    */ \
                                             /* factor, value */                                                   \
    X(mix_color,         3, "fvv",    "v")   /* params: blend (Cycles' NodeMix: 0 mix ... 17 linear light,       */ \
                                             /* 18 clamp unused), clamp factor, clamp result; fac, a, b */         \
    X(mix_float,         1, "fff",    "f")   /* params: clamp factor; fac, a, b */                                 \
    X(mix_vector,        1, "fvv",    "v")   /* params: clamp factor; fac, a, b */                                 \
    X(mix_vector_nonuniform, 1, "vvv", "v")  /* params: clamp factor; fac (per component), a, b */                 \
    X(hue_saturation_value, 0, "ffffv", "v") /* hue, saturation, value, fac, color */                              \
    X(gamma,             0, "vf",     "v")   /* color, gamma */                                                    \
    X(bright_contrast,   0, "vff",    "v")   /* color, bright, contrast */                                         \
    X(invert,            0, "fv",     "v")   /* fac, color */                                                      \
    X(separate_color,    1, "v",      "fff") /* params: mode (0 rgb, 1 hsv, 2 hsl) */                              \
    X(combine_color,     1, "fff",    "v")   /* params: mode */                                                    \
    X(rgb_to_bw,         0, "v",      "f")                                                                         \
    X(blackbody,         0, "f",      "v")   /* temperature (K) */                                                 \
    X(wavelength,        0, "f",      "v")   /* wavelength (nm) */                                                 \
    X(mapping,           1, "vvvv",   "v")   /* params: type (0 point, 1 texture, 2 vector, 3 normal); vector,  */ \
                                             /* location, rotation (euler XYZ), scale */                           \
    X(vector_rotate,     2, "vvvfv",  "v")   /* params: type (0 axis, 1 x, 2 y, 3 z, 4 euler xyz), invert;       */ \
                                             /* vector, center, axis, angle, rotation */                           \
    /* --- the sky (nodes/sky_texture.cpp; last, so that the ids of the ops above stay as they were) --- */     \
    /* params: sky type (0 Preetham, 1 Hosek / Wilkie: evaluated as Preetham, 2 Nishita), sun disc (0, 1),     */ \
    /* settings (tables offset of kSkySettingsFloats: sun direction xyz, turbidity, ground albedo, sun size,     */ \
    /* sun intensity, sun elevation, sun rotation, altitude, air, dust, ozone density), precomputed (tables     */ \
    /* offset of the sky's precomputed data, -1: finalize_program computes it, nodes/sky_texture.h); vector;    */ \
    /* color */                                                                                                   \
    X(sky_texture,       4, "v",      "v")
// clang-format on

enum class ShaderOp : int32_t {
#define PS_SHADER_OP_ENUM(name, params, inputs, outputs) name,
    PS_SHADER_OPS(PS_SHADER_OP_ENUM)
#undef PS_SHADER_OP_ENUM
};

struct ShaderOpInfo {
    const char* name;
    int params;
    const char* inputs;   // one character per input: 'f' float, 'v' vector
    const char* outputs;  // the same for outputs
};
int shader_op_count();
const ShaderOpInfo& shader_op_info(ShaderOp op);

// What a program may set, beside registers.
enum class ProgramTarget : uint8_t {
    closure_color,           // Closure::color (the weight) of closure `index`, vector
    closure_specular_color,  // Closure::specular_color, vector
    closure_roughness,       // Closure::roughness, float
    closure_alpha_x,         // Closure::alpha_x, float
    closure_alpha_y,         // Closure::alpha_y, float
    closure_ior,             // Closure::ior, float
    emission,                // Material::emission, vector
    normal,                  // the shading normal (world space, facing anywhere: made to face wo), vector
};
const char* to_string(ProgramTarget t);
ProgramTarget program_target_from_string(const std::string& name);  // throws InvalidInput

struct ProgramOutput {
    ProgramTarget target = ProgramTarget::closure_color;
    int32_t index = 0;     // the closure, for closure_* targets
    int32_t register_ = 0; // where the value is (first of three for vectors)
};

struct ShaderProgram {
    std::vector<int32_t> code;
    std::vector<float> registers;  // initial values; the register file's size
    std::vector<float> tables;
    std::vector<ProgramOutput> outputs;

    bool empty() const { return code.empty() && outputs.empty(); }
    bool uses_globals = false;  // set by finalize_program: an instruction reads the shading point
};

struct MeshData;
struct Instance;

// Everything about the shading point that a node can read (shader_globals.h fills it from a hit). Positions are
// in world space (render space + Scene::origin(), what Blender calls world space); directions are unit.
struct ShaderGlobals {
    glm::vec3 P{0.0f};               // position
    glm::vec3 N{0.0f, 0.0f, 1.0f};   // shading normal, facing the incoming ray (Cycles flips it on back faces)
    glm::vec3 Ng{0.0f, 0.0f, 1.0f};  // geometric normal, the same side
    glm::vec3 I{0.0f, 0.0f, 1.0f};   // towards where the ray came from
    // Cycles 3.4's compact differential: the footprint dP of the ray at P, and the offsets a Bump node's height
    // is evaluated at, dP times two orthonormal directions about Ng (Cycles' differential_from_compact).
    float dP = 0.0f;
    glm::vec3 dPdx{0.0f}, dPdy{0.0f};
    // The hit on its mesh: the triangle, its barycentrics (u, v of the 2nd and 3rd corners) and their changes
    // along dPdx and dPdy (for UVs and attributes at a bump offset). mesh == nullptr: no mesh (a test's point).
    const MeshData* mesh = nullptr;
    const Instance* instance = nullptr;
    uint32_t triangle = 0;
    glm::vec2 bary{0.0f}, dbary_dx{0.0f}, dbary_dy{0.0f};
    glm::vec3 object_position{0.0f};  // P in the object's own coordinates (Blender's object space)
    glm::mat3 world_to_object_linear{1.0f};  // the object transform's inverse linear part
    glm::mat3 object_to_world_linear{1.0f};
    bool backfacing = false;
    // The world, evaluated for a ray that left the scene (world.h): P is the ray's direction, N = Ng = I = -P,
    // and the generated, object, camera, window and reflection coordinates are Cycles' for the background.
    bool background = false;
    // Light Path: what kind of ray arrived
    bool camera_ray = true, shadow_ray = false, diffuse_ray = false, glossy_ray = false, singular_ray = false,
         transmission_ray = false;
    float ray_length = 0.0f, ray_depth = 0.0f;
};

// The camera as Camera Data and the camera / window texture coordinates see it (Scene::shader_camera).
struct ShaderCamera {
    glm::mat4 world_to_camera{1.0f};  // Cycles' camera space: +Z forward, +Y up
    glm::mat4 world_to_ndc{1.0f};     // clip space of the camera, then x, y mapped to [0, 1] across the frame
    glm::vec3 position{0.0f};         // world space
    bool orthographic = false;
    // A pixel's footprint: per unit of distance (perspective) or its size (orthographic); 0 when no camera
    // was set. Sets ShaderGlobals::dP at camera hits, as Cycles' ray differentials do.
    float pixel_spread = 0.0f;
};

class Scene;

// Checks a program against the op table (counts, register ranges, vector operands, table ranges, outputs'
// closure indices below `closure_count`); `where` names it. Throws InvalidInput.
void validate(const ShaderProgram& p, int closure_count, const std::string& where);

// Folds every instruction whose inputs are constant and which does not read the shading point (evaluating it
// once), drops instructions nothing reads, and sets uses_globals. A program left with no instructions keeps its
// outputs, which then read constant registers.
void finalize_program(ShaderProgram& p, const Scene& scene);

// Runs the program: `registers` must hold p.registers.size() floats, initialised from p.registers.
void run_program(const ShaderProgram& p, const Scene& scene, const ShaderGlobals& g, float* registers);

}  // namespace ps
