// The procedural texture ops (nodes/texture_nodes.cpp, nodes/noise.cpp) against Blender 3.4's Cycles itself.
//
// The goldens (golden/texture_goldens.h) are Cycles' renders, not this code's output. They were produced with
//     blender -b --factory-startup --python tests/native/golden/make_texture_goldens.py
// (Debian's /usr/bin/blender 3.4.1, Cycles CPU, 1 sample, filter width 0.01, no denoising, view transform
// Standard, look None, float OpenEXR read back with bpy.data.images.load). Each of the 32 pixels of a render is a
// quad whose face attributes feed the texture node's Vector and W exactly; the node's outputs drive an Emission
// shader of strength 1 (directly or three floats at a time through Combine XYZ). The script says more, and checks
// first that the pipeline returns the attributes bit-exact.
//
// Tolerances (absolute, scaled by max(1, |value|)): 1e-4 for the deterministic ops (Voronoi, White Noise, Magic,
// Brick, Checker, Gradient), 1e-3 for those built on Perlin noise (Noise, Musgrave, Wave), where at detail 15 one
// ulp of rounding upstream moves the finest octave. noise.cpp follows the AVX2 kernel's rounding closely enough
// that the errors measured are far below both (the test prints each op's largest: about 1e-5 for Noise, under
// 2e-6 for the rest).
//
// Besides the goldens: modes out of range give zeros, ops not ours are refused, and non-finite or huge inputs
// neither crash nor hang.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "golden/texture_goldens.h"
#include "nodes/noise.h"
#include "photonsplat/shader_program.h"
#include "shader/op_args.h"

namespace ps {
namespace {

struct Layout {
    int params;
    const char* inputs;
    const char* outputs;
};

// The op table's layout, read from the table itself (shader_op_info lives in another source file).
Layout layout_of(ShaderOp op) {
    switch (op) {
#define PS_TEST_LAYOUT(name, params, inputs, outputs) \
    case ShaderOp::name: return {params, inputs, outputs};
        PS_SHADER_OPS(PS_TEST_LAYOUT)
#undef PS_TEST_LAYOUT
    }
    return {0, "", ""};
}

int width(char kind) { return kind == 'v' ? 3 : 1; }

// One instruction's register file: inputs first, then outputs, each output pre-filled with a sentinel.
struct Instruction {
    ShaderOp op;
    Layout layout;
    std::vector<int32_t> params, in, out;
    std::vector<float> reg;
    static constexpr float kSentinel = 12345.0f;

    Instruction(ShaderOp op_, std::vector<int32_t> params_) : op(op_), layout(layout_of(op_)), params(params_) {
        params.resize(static_cast<size_t>(layout.params) + 1, 0);
        int r = 0;
        for (const char* k = layout.inputs; *k; ++k) in.push_back(r), r += width(*k);
        for (const char* k = layout.outputs; *k; ++k) out.push_back(r), r += width(*k);
        reg.assign(static_cast<size_t>(r), 0.0f);
        in.push_back(0);
        out.push_back(0);
    }
    int n_inputs() const { return static_cast<int>(std::string(layout.inputs).size()); }
    int n_outputs() const { return static_cast<int>(std::string(layout.outputs).size()); }
    void set_input(int i, float v) { reg[static_cast<size_t>(in[static_cast<size_t>(i)])] = v; }
    void set_input(int i, float x, float y, float z) {
        const size_t b = static_cast<size_t>(in[static_cast<size_t>(i)]);
        reg[b] = x, reg[b + 1] = y, reg[b + 2] = z;
    }
    // All inputs from a flat list in op-table order (vectors as three floats).
    void set_inputs(const float* values) {
        size_t k = 0;
        for (int i = 0; i < n_inputs(); ++i)
            for (int c = 0; c < width(layout.inputs[i]); ++c)
                reg[static_cast<size_t>(in[static_cast<size_t>(i)] + c)] = values[k++];
    }
    bool run() {
        for (int o = 0; o < n_outputs(); ++o)
            for (int c = 0; c < width(layout.outputs[o]); ++c)
                reg[static_cast<size_t>(out[static_cast<size_t>(o)] + c)] = kSentinel;
        OpArgs a{params.data(), in.data(), out.data(), reg.data()};
        return run_texture_op(op, a, nullptr);
    }
    // The outputs flattened in op-table order.
    std::vector<float> outputs() const {
        std::vector<float> v;
        for (int o = 0; o < n_outputs(); ++o)
            for (int c = 0; c < width(layout.outputs[o]); ++c)
                v.push_back(reg[static_cast<size_t>(out[static_cast<size_t>(o)] + c)]);
        return v;
    }
};

bool perlin_based(ShaderOp op) {
    return op == ShaderOp::noise_texture || op == ShaderOp::musgrave_texture || op == ShaderOp::wave_texture;
}

const char* op_name(ShaderOp op) {
    switch (op) {
#define PS_TEST_NAME(name, params, inputs, outputs) \
    case ShaderOp::name: return #name;
        PS_SHADER_OPS(PS_TEST_NAME)
#undef PS_TEST_NAME
    }
    return "?";
}

TEST(TextureNodes, MatchCyclesGoldens) {
    std::map<std::string, std::pair<double, std::string>> max_error;  // per op: error over max(1, |value|), where
    int compared = 0;
    for (const auto& c : texture_goldens::kCases) {
        Instruction ins(c.op, std::vector<int32_t>(c.params, c.params + c.n_params));
        ASSERT_EQ(ins.layout.params, c.n_params) << c.label;
        ins.set_inputs(c.inputs);
        const bool has_w = c.op == ShaderOp::noise_texture || c.op == ShaderOp::voronoi_texture ||
                           c.op == ShaderOp::musgrave_texture || c.op == ShaderOp::white_noise_texture;  // input 1
        const double tol = perlin_based(c.op) ? 1e-3 : 1e-4;
        const int stride = 4 + c.out_width;
        for (int p = 0; p < c.n_points; ++p) {
            const float* row = c.data + p * stride;
            ins.set_input(0, row[0], row[1], row[2]);
            if (has_w) ins.set_input(1, row[3]);
            ASSERT_TRUE(ins.run()) << c.label;
            const std::vector<float> got = ins.outputs();
            ASSERT_EQ(static_cast<int>(got.size()), c.out_width) << c.label;
            for (int k = 0; k < c.out_width; ++k) {
                const float want = row[4 + k];
                if (std::isnan(want)) continue;  // an output the node does not show
                const double err = std::fabs(static_cast<double>(got[static_cast<size_t>(k)]) - want) /
                                   std::max(1.0, std::fabs(static_cast<double>(want)));
                auto& m = max_error[op_name(c.op)];
                if (m.second.empty() || !(err <= m.first)) m = {std::isnan(err) ? 1e30 : err, c.label};
                ++compared;
                EXPECT_LE(err, tol) << c.label << ", point " << p << " (" << row[0] << ", " << row[1] << ", "
                                    << row[2] << ", w " << row[3] << "), output component " << k << ": got "
                                    << got[static_cast<size_t>(k)] << ", Cycles " << want;
            }
        }
    }
    EXPECT_GT(compared, 5000);
    for (const auto& [op, err] : max_error)
        std::printf("  %-20s max error %.3g (%s)\n", op.c_str(), err.first, err.second.c_str());
}

// Every op's modes, for the robustness tests: the params' valid ranges.
struct OpModes {
    ShaderOp op;
    std::vector<std::vector<int32_t>> valid;  // each a full param list
};

std::vector<OpModes> all_modes() {
    std::vector<OpModes> m;
    OpModes noise{ShaderOp::noise_texture, {}}, voronoi{ShaderOp::voronoi_texture, {}},
        musgrave{ShaderOp::musgrave_texture, {}}, wave{ShaderOp::wave_texture, {}}, magic{ShaderOp::magic_texture, {}},
        brick{ShaderOp::brick_texture, {}}, checker{ShaderOp::checker_texture, {{}}},
        gradient{ShaderOp::gradient_texture, {}}, white{ShaderOp::white_noise_texture, {}};
    for (int d = 1; d <= 4; ++d) {
        noise.valid.push_back({d});
        white.valid.push_back({d});
        for (int f = 0; f < 5; ++f)
            for (int k = 0; k < 4; ++k) voronoi.valid.push_back({d, f, k});
        for (int t = 0; t < 5; ++t) musgrave.valid.push_back({d, t});
    }
    for (int t = 0; t < 2; ++t)
        for (int b = 0; b < 4; ++b)
            for (int p = 0; p < 3; ++p) wave.valid.push_back({t, b, b, p});
    for (int d = 0; d <= 10; ++d) magic.valid.push_back({d});
    brick.valid = {{2, 2}, {0, 0}, {1, 99}, {99, 1}};
    for (int t = 0; t < 7; ++t) gradient.valid.push_back({t});
    return {noise, voronoi, musgrave, wave, magic, brick, checker, gradient, white};
}

TEST(TextureNodes, ModesOutOfRangeGiveZeros) {
    const std::vector<std::pair<ShaderOp, std::vector<std::vector<int32_t>>>> invalid = {
        {ShaderOp::noise_texture, {{0}, {5}, {-1}}},
        {ShaderOp::voronoi_texture, {{0, 0, 0}, {5, 0, 0}, {3, 5, 0}, {3, -1, 0}, {3, 0, 4}, {3, 0, -1}}},
        {ShaderOp::musgrave_texture, {{0, 0}, {5, 0}, {3, 5}, {3, -1}}},
        {ShaderOp::wave_texture, {{2, 0, 0, 0}, {-1, 0, 0, 0}, {0, 4, 0, 0}, {1, 0, 4, 0}, {0, 0, 0, 3}, {0, 0, -1, 0}}},
        {ShaderOp::magic_texture, {{-1}, {11}, {1000}}},
        {ShaderOp::brick_texture, {{-1, 2}, {2, -1}, {100, 2}, {2, 100}}},
        {ShaderOp::gradient_texture, {{-1}, {7}}},
        {ShaderOp::white_noise_texture, {{0}, {5}}},
    };
    for (const auto& [op, params_list] : invalid) {
        for (const auto& params : params_list) {
            Instruction ins(op, params);
            std::vector<float> values(64, 0.7f);
            ins.set_inputs(values.data());
            ASSERT_TRUE(ins.run()) << op_name(op);
            for (float v : ins.outputs()) EXPECT_EQ(v, 0.0f) << op_name(op) << " param " << params[0];
        }
    }
}

TEST(TextureNodes, RefusesOpsNotItsOwn) {
    for (ShaderOp op : {ShaderOp::copy_float, ShaderOp::image_texture, ShaderOp::math, ShaderOp::mix_color}) {
        Instruction ins(op, {});
        EXPECT_FALSE(ins.run()) << op_name(op);
    }
}

TEST(TextureNodes, DiscardedOutputsAreNotWritten) {
    // An output register of -1 (an unused socket) must be skipped, not written through.
    for (const auto& m : all_modes()) {
        Instruction ins(m.op, m.valid.front());
        std::vector<float> values(64, 0.3f);
        ins.set_inputs(values.data());
        for (int o = 0; o < ins.n_outputs(); ++o) ins.out[static_cast<size_t>(o)] = -1;
        OpArgs a{ins.params.data(), ins.in.data(), ins.out.data(), ins.reg.data()};
        const std::vector<float> before = ins.reg;
        EXPECT_TRUE(run_texture_op(m.op, a, nullptr));
        EXPECT_EQ(ins.reg, before) << op_name(m.op);
    }
}

TEST(TextureNodes, NonFiniteAndHugeInputsNeitherCrashNorHang) {
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> specials = {nan, inf, -inf, 1e30f, -1e30f, 3e9f, -3e9f, 0.0f, -0.0f, 1e-30f};
    int runs = 0;
    for (const auto& m : all_modes()) {
        for (const auto& params : m.valid) {
            Instruction ins(m.op, params);
            int n_floats = 0;
            for (const char* k = ins.layout.inputs; *k; ++k) n_floats += width(*k);
            // Each input float in turn set to each special value, the others ordinary.
            for (int i = 0; i < n_floats; ++i) {
                for (float s : specials) {
                    std::vector<float> values(static_cast<size_t>(n_floats), 0.6f);
                    values[static_cast<size_t>(i)] = s;
                    ins.set_inputs(values.data());
                    ASSERT_TRUE(ins.run());
                    ++runs;
                }
            }
            // Everything at once.
            for (float s : specials) {
                std::vector<float> values(static_cast<size_t>(n_floats), s);
                ins.set_inputs(values.data());
                ASSERT_TRUE(ins.run());
            }
        }
    }
    EXPECT_GT(runs, 10000);
}

TEST(TextureNodes, FloatToIntIsX86Truncation) {
    EXPECT_EQ(noise::float_to_int(2.9f), 2);
    EXPECT_EQ(noise::float_to_int(-2.9f), -2);
    EXPECT_EQ(noise::float_to_int(-2147483648.0f), INT32_MIN);
    EXPECT_EQ(noise::float_to_int(2147483648.0f), INT32_MIN);
    EXPECT_EQ(noise::float_to_int(std::numeric_limits<float>::quiet_NaN()), INT32_MIN);
    EXPECT_EQ(noise::float_to_int(-std::numeric_limits<float>::infinity()), INT32_MIN);
    EXPECT_EQ(noise::float_to_int(2147483520.0f), 2147483520);
}

TEST(TextureNodes, HashIsLookup3AsCyclesSeedsIt) {
    // hash_uint(0): lookup3's final() on a = b = c = 0xdeadbeef + 4 + 13, worked by hand below.
    auto rot = [](uint32_t x, int k) { return (x << k) | (x >> (32 - k)); };
    uint32_t a = 0xdeadbeefu + 17u, b = a, c = a;
    c ^= b; c -= rot(b, 14); a ^= c; a -= rot(c, 11); b ^= a; b -= rot(a, 25); c ^= b; c -= rot(b, 16);
    a ^= c; a -= rot(c, 4); b ^= a; b -= rot(a, 14); c ^= b; c -= rot(b, 24);
    EXPECT_EQ(noise::hash_uint(0), c);
    // Different arities and argument orders differ.
    EXPECT_NE(noise::hash_uint2(1, 2), noise::hash_uint2(2, 1));
    EXPECT_NE(noise::hash_uint3(1, 2, 3), noise::hash_uint4(1, 2, 3, 0));
    // [0, 1] with both ends reachable in principle; a sample stays inside.
    for (uint32_t i = 0; i < 1000; ++i) {
        const float f = noise::hash_uint_to_float(i);
        EXPECT_GE(f, 0.0f);
        EXPECT_LE(f, 1.0f);
    }
}

}  // namespace
}  // namespace ps
