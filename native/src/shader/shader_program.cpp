// The shader program interpreter: the op table, validation, constant folding and the loop that runs a program
// at a hit. The ops themselves live by group: shading_point_ops.cpp (what the hit is), image_ops.cpp (images),
// nodes/texture_nodes.cpp (procedural textures), nodes/converter_nodes.cpp (maths and colour).
#include "photonsplat/shader_program.h"

#include <cmath>
#include <cstring>

#include "photonsplat/errors.h"
#include "photonsplat/scene.h"
#include "nodes/color_math.h"
#include "nodes/sky_texture.h"
#include "shader/op_args.h"

namespace ps {

namespace {

constexpr ShaderOpInfo kOps[] = {
#define PS_SHADER_OP_INFO(name, params, inputs, outputs) {#name, params, inputs, outputs},
    PS_SHADER_OPS(PS_SHADER_OP_INFO)
#undef PS_SHADER_OP_INFO
};
constexpr int kOpCount = static_cast<int>(sizeof(kOps) / sizeof(kOps[0]));

// Limits that keep a hostile program finite: a real material compiles to a few hundred instructions.
constexpr size_t kMaxCodeWords = size_t(1) << 22;
constexpr size_t kMaxRegisters = size_t(1) << 20;
constexpr size_t kMaxTableFloats = size_t(1) << 24;

int width(char type) { return type == 'v' ? 3 : 1; }

bool is_vector_target(ProgramTarget t) {
    return t == ProgramTarget::closure_color || t == ProgramTarget::closure_specular_color ||
           t == ProgramTarget::emission || t == ProgramTarget::normal;
}

// Ops whose result depends on more than their inputs: never folded.
bool reads_shading_point(ShaderOp op, const int32_t* params) {
    switch (op) {
        case ShaderOp::texture_coordinate:
        case ShaderOp::uv_map:
        case ShaderOp::attribute:
        case ShaderOp::geometry:
        case ShaderOp::object_info:
        case ShaderOp::light_path:
        case ShaderOp::camera_data:
        case ShaderOp::fresnel:
        case ShaderOp::layer_weight:
        case ShaderOp::normal_map:
        case ShaderOp::bump:
        case ShaderOp::vector_transform: return true;
        case ShaderOp::image_texture: return params[3] == 1;  // box projection reads the normal
        default: return false;
    }
}

// One decoded instruction.
struct Decoded {
    ShaderOp op;
    const int32_t* params;
    const int32_t* in;
    const int32_t* out;
    int n_params, n_in, n_out;
    size_t next;  // index of the next instruction's first word
};

Decoded decode(const std::vector<int32_t>& code, size_t pc) {
    Decoded d;
    d.op = static_cast<ShaderOp>(code[pc]);
    d.n_params = code[pc + 1];
    d.n_in = code[pc + 2];
    d.n_out = code[pc + 3];
    d.params = code.data() + pc + 4;
    d.in = d.params + d.n_params;
    d.out = d.in + d.n_in;
    d.next = pc + 4 + d.n_params + d.n_in + d.n_out;
    return d;
}

void run_move(ShaderOp op, const OpArgs& a) {
    switch (op) {
        case ShaderOp::copy_float: a.set(0, a.f(0)); break;
        case ShaderOp::copy_vector: a.set(0, a.v(0)); break;
        case ShaderOp::combine_xyz: a.set(0, glm::vec3(a.f(0), a.f(1), a.f(2))); break;
        case ShaderOp::color_to_float: a.set(0, cycles_luminance(a.v(0))); break;
        case ShaderOp::vector_to_float: {
            const glm::vec3 v = a.v(0);
            a.set(0, (v.x + v.y + v.z) * (1.0f / 3.0f));
            break;
        }
        case ShaderOp::float_to_vector: a.set(0, glm::vec3(a.f(0))); break;
        default: break;
    }
}

void run_instruction(const Decoded& d, const ShaderProgram& p, const Scene& scene, const ShaderGlobals& g,
                     float* registers) {
    const OpArgs a{d.params, d.in, d.out, registers};
    const float* tables = p.tables.data();
    if (d.op <= ShaderOp::float_to_vector) {
        run_move(d.op, a);
        return;
    }
    if (run_shading_point_op(d.op, a, tables, scene, g)) return;
    if (run_image_op(d.op, a, scene, g)) return;
    if (run_texture_op(d.op, a, tables)) return;
    if (run_sky_op(d.op, a, tables)) return;
    run_converter_op(d.op, a, tables);
}

}  // namespace

int shader_op_count() { return kOpCount; }

const ShaderOpInfo& shader_op_info(ShaderOp op) { return kOps[static_cast<int>(op)]; }

const char* to_string(ProgramTarget t) {
    switch (t) {
        case ProgramTarget::closure_color: return "closure_color";
        case ProgramTarget::closure_specular_color: return "closure_specular_color";
        case ProgramTarget::closure_roughness: return "closure_roughness";
        case ProgramTarget::closure_alpha_x: return "closure_alpha_x";
        case ProgramTarget::closure_alpha_y: return "closure_alpha_y";
        case ProgramTarget::closure_ior: return "closure_ior";
        case ProgramTarget::emission: return "emission";
        case ProgramTarget::normal: return "normal";
    }
    return "?";
}

ProgramTarget program_target_from_string(const std::string& name) {
    for (int i = 0; i <= static_cast<int>(ProgramTarget::normal); ++i)
        if (name == to_string(static_cast<ProgramTarget>(i))) return static_cast<ProgramTarget>(i);
    throw InvalidInput("program.outputs.target",
                       "must be closure_color, closure_specular_color, closure_roughness, closure_alpha_x, "
                       "closure_alpha_y, closure_ior, emission or normal, got '" + name + "'");
}

void validate(const ShaderProgram& p, int closure_count, const std::string& where) {
    const size_t registers = p.registers.size();
    if (p.code.size() > kMaxCodeWords) throw InvalidInput(where + ".code", "too long");
    if (registers > kMaxRegisters) throw InvalidInput(where + ".registers", "too many registers");
    if (p.tables.size() > kMaxTableFloats) throw InvalidInput(where + ".tables", "too large");
    for (size_t r = 0; r < registers; ++r)
        if (!std::isfinite(p.registers[r]))
            throw InvalidInput(where + ".registers", "register " + std::to_string(r) + " is NaN or infinite");
    for (size_t i = 0; i < p.tables.size(); ++i)
        if (!std::isfinite(p.tables[i]))
            throw InvalidInput(where + ".tables", "value " + std::to_string(i) + " is NaN or infinite");
    const auto fits = [&](int32_t r, int w) { return r >= 0 && static_cast<size_t>(r) + w <= registers; };
    const auto table_fits = [&](int32_t offset, int64_t count) {
        return offset >= 0 && count >= 0 && static_cast<uint64_t>(offset) + static_cast<uint64_t>(count) <= p.tables.size();
    };
    size_t pc = 0;
    int index = 0;
    while (pc < p.code.size()) {
        const std::string at = where + ".code[" + std::to_string(pc) + "] (instruction " + std::to_string(index) + ")";
        if (pc + 4 > p.code.size()) throw InvalidInput(at, "truncated instruction");
        const int32_t op = p.code[pc];
        if (op < 0 || op >= kOpCount) throw InvalidInput(at, "unknown op " + std::to_string(op));
        const ShaderOpInfo& info = kOps[op];
        const int n_in = static_cast<int>(std::strlen(info.inputs)), n_out = static_cast<int>(std::strlen(info.outputs));
        if (p.code[pc + 1] != info.params || p.code[pc + 2] != n_in || p.code[pc + 3] != n_out)
            throw InvalidInput(at, std::string(info.name) + " takes " + std::to_string(info.params) + " params, " +
                                       std::to_string(n_in) + " inputs and " + std::to_string(n_out) + " outputs");
        if (pc + 4 + info.params + n_in + n_out > p.code.size()) throw InvalidInput(at, "truncated instruction");
        const Decoded d = decode(p.code, pc);
        for (int i = 0; i < n_in; ++i)
            if (!fits(d.in[i], width(info.inputs[i])))
                throw InvalidInput(at, std::string(info.name) + " input " + std::to_string(i) + " reads register " +
                                           std::to_string(d.in[i]) + " of " + std::to_string(registers));
        for (int o = 0; o < n_out; ++o)
            if (d.out[o] != -1 && !fits(d.out[o], width(info.outputs[o])))
                throw InvalidInput(at, std::string(info.name) + " output " + std::to_string(o) + " writes register " +
                                           std::to_string(d.out[o]) + " of " + std::to_string(registers));
        // Tables the op reads.
        bool tables_ok = true;
        switch (d.op) {
            case ShaderOp::texture_coordinate: tables_ok = d.params[1] == -1 || table_fits(d.params[1], 16); break;
            case ShaderOp::color_ramp: tables_ok = d.params[1] >= 1 && table_fits(d.params[0], int64_t(d.params[1]) * 4); break;
            case ShaderOp::rgb_curves:
            case ShaderOp::vector_curves:
                tables_ok = d.params[1] >= 1 && table_fits(d.params[0], 2 + int64_t(d.params[1]) * 3);
                break;
            case ShaderOp::float_curve: tables_ok = d.params[1] >= 1 && table_fits(d.params[0], 2 + int64_t(d.params[1])); break;
            case ShaderOp::sky_texture:
                tables_ok = table_fits(d.params[2], kSkySettingsFloats) &&
                            (d.params[3] == -1 || table_fits(d.params[3], sky_precomputed_floats(d.params[0])));
                break;
            default: break;
        }
        if (!tables_ok) throw InvalidInput(at, std::string(info.name) + " reads beyond the program's tables");
        pc = d.next;
        ++index;
    }
    for (size_t k = 0; k < p.outputs.size(); ++k) {
        const ProgramOutput& o = p.outputs[k];
        const std::string at = where + ".outputs[" + std::to_string(k) + "]";
        if (o.target > ProgramTarget::normal) throw InvalidInput(at, "unknown target");
        if (!fits(o.register_, is_vector_target(o.target) ? 3 : 1))
            throw InvalidInput(at + ".register", "is " + std::to_string(o.register_) + ", the program has " +
                                                     std::to_string(registers) + " registers");
        const bool closure = o.target != ProgramTarget::emission && o.target != ProgramTarget::normal;
        if (closure && (o.index < 0 || o.index >= closure_count))
            throw InvalidInput(at + ".index", "is " + std::to_string(o.index) + ", the material has " +
                                                  std::to_string(closure_count) + " closures");
    }
}

void finalize_program(ShaderProgram& p, const Scene& scene) {
    // Textures the image ops name must exist.
    for (size_t pc = 0; pc < p.code.size();) {
        const Decoded d = decode(p.code, pc);
        if (d.op == ShaderOp::image_texture || d.op == ShaderOp::environment_texture) {
            const int32_t t = d.params[0];
            if (t < 0 || static_cast<size_t>(t) >= scene.textures().size())
                throw InvalidInput("program." + std::string(shader_op_info(d.op).name) + ".texture",
                                   "is " + std::to_string(t) + ", but the scene has " +
                                       std::to_string(scene.textures().size()) + " textures");
        }
        pc = d.next;
    }

    // Sky textures: what Cycles precomputes per node on the host, computed here once per program (a program
    // naming the same sky twice shares one copy) into its tables, where the op's last param then points.
    std::vector<std::pair<std::vector<int32_t>, int32_t>> skies;  // (type, disc, settings bits) → offset
    for (size_t pc = 0; pc < p.code.size();) {
        const Decoded d = decode(p.code, pc);
        if (d.op == ShaderOp::sky_texture && d.params[3] == -1 && sky_precomputed_floats(d.params[0]) > 0 &&
            d.params[2] >= 0 && static_cast<size_t>(d.params[2]) + kSkySettingsFloats <= p.tables.size()) {
            std::vector<int32_t> key{d.params[0], d.params[1] != 0};
            float settings[kSkySettingsFloats];
            for (int i = 0; i < kSkySettingsFloats; ++i) {
                settings[i] = p.tables[static_cast<size_t>(d.params[2]) + i];
                int32_t bits;
                std::memcpy(&bits, &settings[i], sizeof bits);
                key.push_back(bits);
            }
            int32_t offset = -1;
            for (const auto& sky : skies)
                if (sky.first == key) offset = sky.second;
            if (offset < 0) {
                if (p.tables.size() + static_cast<size_t>(sky_precomputed_floats(d.params[0])) > kMaxTableFloats)
                    throw InvalidInput("program.sky_texture", "too many different skies in one program");
                offset = static_cast<int32_t>(p.tables.size());
                precompute_sky(d.params[0], d.params[1] != 0, settings, p.tables);
                skies.emplace_back(std::move(key), offset);
            }
            p.code[pc + 4 + 3] = offset;
        }
        pc = d.next;
    }

    // Fold: run every instruction whose inputs are all constant and which reads nothing of the hit, once, into
    // the initial registers (programs are written once per register, as the add-on compiles them).
    const size_t n = p.registers.size();
    std::vector<char> varying(n, 0);  // written by an instruction that stays
    std::vector<size_t> kept;         // start of each kept instruction
    const ShaderGlobals none;
    for (size_t pc = 0; pc < p.code.size();) {
        const Decoded d = decode(p.code, pc);
        const ShaderOpInfo& info = kOps[static_cast<int>(d.op)];
        bool constant = !reads_shading_point(d.op, d.params);
        for (int i = 0; constant && i < d.n_in; ++i)
            for (int k = 0; k < width(info.inputs[i]); ++k)
                if (varying[d.in[i] + k]) constant = false;
        if (constant) {
            run_instruction(d, p, scene, none, p.registers.data());
            for (size_t r = 0; r < n; ++r)
                if (!std::isfinite(p.registers[r])) p.registers[r] = 0.0f;  // as run_program's outputs
        } else {
            kept.push_back(pc);
            for (int o = 0; o < d.n_out; ++o)
                if (d.out[o] >= 0)
                    for (int k = 0; k < width(info.outputs[o]); ++k) varying[d.out[o] + k] = 1;
        }
        pc = d.next;
    }

    // Drop what no output needs, walking backwards from the outputs.
    std::vector<char> live(n, 0);
    for (const ProgramOutput& o : p.outputs)
        for (int k = 0; k < (is_vector_target(o.target) ? 3 : 1); ++k) live[o.register_ + k] = 1;
    std::vector<char> keep(kept.size(), 0);
    for (size_t j = kept.size(); j-- > 0;) {
        const Decoded d = decode(p.code, kept[j]);
        const ShaderOpInfo& info = kOps[static_cast<int>(d.op)];
        bool needed = false;
        for (int o = 0; o < d.n_out && !needed; ++o)
            if (d.out[o] >= 0)
                for (int k = 0; k < width(info.outputs[o]); ++k)
                    if (live[d.out[o] + k]) needed = true;
        if (!needed) continue;
        keep[j] = 1;
        for (int i = 0; i < d.n_in; ++i)
            for (int k = 0; k < width(info.inputs[i]); ++k) live[d.in[i] + k] = 1;
    }
    std::vector<int32_t> code;
    p.uses_globals = false;
    for (size_t j = 0; j < kept.size(); ++j) {
        if (!keep[j]) continue;
        const Decoded d = decode(p.code, kept[j]);
        code.insert(code.end(), p.code.begin() + kept[j], p.code.begin() + d.next);
        if (reads_shading_point(d.op, d.params)) p.uses_globals = true;
    }
    p.code = std::move(code);
}

void run_program(const ShaderProgram& p, const Scene& scene, const ShaderGlobals& g, float* registers) {
    for (size_t pc = 0; pc < p.code.size();) {
        const Decoded d = decode(p.code, pc);
        run_instruction(d, p, scene, g, registers);
        pc = d.next;
    }
}

}  // namespace ps
