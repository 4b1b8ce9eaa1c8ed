// Converter node ops (nodes/converter_nodes.cpp) against Blender 3.4's Cycles: every case in
// golden/converter_goldens.h is a value Cycles rendered for that node, mode and input (make_converter_goldens.py
// says how), and the op must give it within 1e-4 relative (with a 1e-6 absolute floor for values that cancel to
// about zero). Cycles' film turns a non-finite value into 0, so where the golden is exactly 0 a non-finite result
// passes too. Then: invalid modes give zeros, NaN and infinite inputs never crash, and ops outside the group are
// declined.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "golden/converter_goldens.h"
#include "photonsplat/shader_program.h"
#include "../../native/src/shader/op_args.h"

namespace ps {
namespace {

// The op table's operand types, read from the X-macro itself (the test needs no other project source).
struct Sig {
    int params;
    const char* in;
    const char* out;
};
const Sig kSigs[] = {
#define PS_TEST_SIG(name, params, inputs, outputs) {params, inputs, outputs},
    PS_SHADER_OPS(PS_TEST_SIG)
#undef PS_TEST_SIG
};
const Sig& sig(ShaderOp op) { return kSigs[static_cast<int>(op)]; }

int width(char type) { return type == 'v' ? 3 : 1; }

// One instruction over a register file: inputs first (in order), then every output, each in its own registers.
struct Call {
    std::vector<int32_t> params, in, out;
    std::vector<float> reg;
    std::vector<int> out_at;  // register of each output

    Call(ShaderOp op, const int* p, int n_params, const float* values, int n_values) {
        const Sig& s = sig(op);
        params.assign(p, p + n_params);
        params.resize(std::max<size_t>(params.size(), 3), 0);
        int r = 0;
        for (const char* t = s.in; *t; ++t) {
            in.push_back(r);
            r += width(*t);
        }
        EXPECT_EQ(r, n_values) << "input count";
        reg.assign(values, values + n_values);
        for (const char* t = s.out; *t; ++t) {
            out.push_back(r);
            out_at.push_back(r);
            r += width(*t);
        }
        reg.resize(r, -12345.0f);  // a marker: an output left unwritten shows
    }
    bool run(ShaderOp op, const float* tables) {
        OpArgs a{params.data(), in.data(), out.data(), reg.data()};
        return run_converter_op(op, a, tables);
    }
};

TEST(ConverterNodes, MatchCyclesGoldens) {
    int checked = 0;
    double worst_rel = 0.0;
    std::string worst;
    for (const ConverterGolden& g : kConverterGoldens) {
        Call c(g.op, g.params, g.n_params, g.in, g.n_in);
        const float* table = g.table >= 0 ? kConverterGoldenTables[g.table] : nullptr;
        ASSERT_TRUE(c.run(g.op, table)) << g.label;
        int e = 0;
        for (int k = 0; k < g.n_outs; ++k) {
            const int o = g.outs[k];
            const int w = width(sig(g.op).out[o]);
            for (int j = 0; j < w; ++j, ++e) {
                ASSERT_LT(e, g.n_expect) << g.label;
                const float got = c.reg[c.out_at[o] + j];
                const float want = g.expect[e];
                if (want == 0.0f && !std::isfinite(got)) continue;  // Cycles' film zeroes non-finite values
                const double err = std::fabs(double(got) - double(want));
                EXPECT_LE(err, 1e-4 * std::fabs(double(want)) + 1e-6)
                    << g.label << " component " << j << " of output " << o << ": got " << got << ", Cycles " << want;
                const double rel = err / std::max(std::fabs(double(want)), 1e-2);
                if (rel > worst_rel) {
                    worst_rel = rel;
                    worst = g.label;
                }
                ++checked;
            }
        }
        EXPECT_EQ(e, g.n_expect) << g.label;
    }
    std::printf("checked %d values; worst relative error %.3g (%s)\n", checked, worst_rel, worst.c_str());
}

// Every goldens' op and mode, one value each, is what the set covers; this lists the families so that a regenerated
// file that lost one shows.
TEST(ConverterNodes, GoldensCoverEveryMode) {
    auto count = [](ShaderOp op, int param0) {
        int n = 0;
        for (const ConverterGolden& g : kConverterGoldens)
            if (g.op == op && (param0 < 0 || (g.n_params > 0 && g.params[0] == param0))) ++n;
        return n;
    };
    for (int m = 0; m < 40; ++m) EXPECT_GT(count(ShaderOp::math, m), 0) << "math " << m;
    for (int m = 0; m < 27; ++m) EXPECT_GT(count(ShaderOp::vector_math, m), 0) << "vector math " << m;
    for (int m = 0; m < 18; ++m) EXPECT_GT(count(ShaderOp::mix_color, m), 0) << "mix " << m;
    for (int m = 0; m < 4; ++m) {
        EXPECT_GT(count(ShaderOp::map_range, m), 0) << "map range " << m;
        EXPECT_GT(count(ShaderOp::map_range_vector, m), 0) << "vector map range " << m;
        EXPECT_GT(count(ShaderOp::mapping, m), 0) << "mapping " << m;
    }
    for (int m = 0; m < 5; ++m) EXPECT_GT(count(ShaderOp::vector_rotate, m), 0) << "vector rotate " << m;
    for (int m = 0; m < 3; ++m) {
        EXPECT_GT(count(ShaderOp::separate_color, m), 0);
        EXPECT_GT(count(ShaderOp::combine_color, m), 0);
    }
    for (ShaderOp op : {ShaderOp::clamp, ShaderOp::color_ramp, ShaderOp::rgb_curves, ShaderOp::vector_curves,
                        ShaderOp::float_curve, ShaderOp::mix_float, ShaderOp::mix_vector,
                        ShaderOp::mix_vector_nonuniform, ShaderOp::hue_saturation_value, ShaderOp::gamma,
                        ShaderOp::bright_contrast, ShaderOp::invert, ShaderOp::rgb_to_bw, ShaderOp::blackbody,
                        ShaderOp::wavelength})
        EXPECT_GT(count(op, -1), 0) << static_cast<int>(op);
}

const ShaderOp kConverterOps[] = {
    ShaderOp::math,          ShaderOp::vector_math,       ShaderOp::map_range,  ShaderOp::map_range_vector,
    ShaderOp::clamp,         ShaderOp::color_ramp,        ShaderOp::rgb_curves, ShaderOp::vector_curves,
    ShaderOp::float_curve,   ShaderOp::mix_color,         ShaderOp::mix_float,  ShaderOp::mix_vector,
    ShaderOp::mix_vector_nonuniform, ShaderOp::hue_saturation_value, ShaderOp::gamma, ShaderOp::bright_contrast,
    ShaderOp::invert,        ShaderOp::separate_color,    ShaderOp::combine_color, ShaderOp::rgb_to_bw,
    ShaderOp::blackbody,     ShaderOp::wavelength,        ShaderOp::mapping,    ShaderOp::vector_rotate,
};

bool is_converter(ShaderOp op) {
    for (ShaderOp c : kConverterOps)
        if (c == op) return true;
    return false;
}

std::vector<float> inputs_of(ShaderOp op, float value) {
    int n = 0;
    for (const char* t = sig(op).in; *t; ++t) n += width(*t);
    return std::vector<float>(n, value);
}

TEST(ConverterNodes, DeclinesOtherOps) {
    const int n_ops = static_cast<int>(sizeof(kSigs) / sizeof(kSigs[0]));
    for (int i = 0; i < n_ops; ++i) {
        const ShaderOp op = static_cast<ShaderOp>(i);
        if (is_converter(op)) continue;
        std::vector<float> in = inputs_of(op, 0.5f);
        const int p[3] = {0, 0, 0};
        Call c(op, p, sig(op).params < 3 ? sig(op).params : 3, in.data(), static_cast<int>(in.size()));
        // OpArgs for a foreign op may have other counts; nothing is read when the op is declined.
        EXPECT_FALSE(c.run(op, nullptr)) << i;
    }
}

// Modes outside their enums (and bad table params) give zeros in every output.
TEST(ConverterNodes, InvalidModesGiveZeros) {
    const float table[2 + 3 * 4] = {0.0f, 1.0f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f, 1.0f, 1.1f, 1.2f};
    struct Bad {
        ShaderOp op;
        int params[3];
    };
    const Bad bad[] = {
        {ShaderOp::math, {40, 0, 0}},        {ShaderOp::math, {-1, 0, 0}},          {ShaderOp::math, {0, 2, 0}},
        {ShaderOp::vector_math, {27, 0, 0}}, {ShaderOp::vector_math, {-5, 0, 0}},   {ShaderOp::map_range, {4, 0, 0}},
        {ShaderOp::map_range, {0, 7, 0}},    {ShaderOp::map_range_vector, {9, 0, 0}}, {ShaderOp::clamp, {2, 0, 0}},
        {ShaderOp::color_ramp, {0, 0, 1}},   {ShaderOp::color_ramp, {-1, 3, 1}},    {ShaderOp::color_ramp, {0, 3, 2}},
        {ShaderOp::rgb_curves, {0, 1, 0}},   {ShaderOp::vector_curves, {-2, 4, 0}}, {ShaderOp::float_curve, {0, 1, 0}},
        {ShaderOp::mix_color, {19, 1, 0}},   {ShaderOp::mix_color, {-1, 1, 0}},     {ShaderOp::mix_color, {0, 3, 0}},
        {ShaderOp::mix_float, {2, 0, 0}},    {ShaderOp::mix_vector, {-1, 0, 0}},
        {ShaderOp::mix_vector_nonuniform, {5, 0, 0}}, {ShaderOp::separate_color, {3, 0, 0}},
        {ShaderOp::combine_color, {-1, 0, 0}}, {ShaderOp::mapping, {4, 0, 0}},      {ShaderOp::vector_rotate, {5, 0, 0}},
        {ShaderOp::vector_rotate, {0, 2, 0}},
    };
    for (const Bad& b : bad) {
        std::vector<float> in = inputs_of(b.op, 0.3f);
        Call c(b.op, b.params, sig(b.op).params, in.data(), static_cast<int>(in.size()));
        ASSERT_TRUE(c.run(b.op, table));
        for (size_t r = in.size(); r < c.reg.size(); ++r)
            EXPECT_EQ(c.reg[r], 0.0f) << "op " << static_cast<int>(b.op) << " mode " << b.params[0];
    }
    // A null table is as bad as a missing one.
    std::vector<float> in = inputs_of(ShaderOp::float_curve, 0.3f);
    const int p[2] = {0, 4};
    Call c(ShaderOp::float_curve, p, 2, in.data(), static_cast<int>(in.size()));
    ASSERT_TRUE(c.run(ShaderOp::float_curve, nullptr));
    EXPECT_EQ(c.reg.back(), 0.0f);
}

// NaN and ±inf through every op and mode: the op must return (no crash, no hang, sanitizers quiet) and write every
// output. Tables get a zero-width range too (its lookups divide by zero).
TEST(ConverterNodes, NonFiniteInputsAreSafe) {
    const float table[2 + 3 * 4] = {0.5f, 0.5f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f, 1.0f, 1.1f, 1.2f};
    const float specials[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                              -std::numeric_limits<float>::infinity(), 3.0e38f, -3.0e38f, 0.0f};
    for (ShaderOp op : kConverterOps) {
        for (int mode = 0; mode < 41; ++mode) {
            for (float v : specials) {
                std::vector<float> in = inputs_of(op, v);
                int p[3] = {mode, 1, 1};
                if (op == ShaderOp::color_ramp || op == ShaderOp::rgb_curves || op == ShaderOp::vector_curves ||
                    op == ShaderOp::float_curve) {
                    p[0] = 0;
                    p[1] = op == ShaderOp::color_ramp ? 3 : 4;
                    p[2] = mode & 1;
                }
                Call c(op, p, sig(op).params, in.data(), static_cast<int>(in.size()));
                ASSERT_TRUE(c.run(op, table));
                for (size_t r = in.size(); r < c.reg.size(); ++r)
                    EXPECT_NE(c.reg[r], -12345.0f) << "op " << static_cast<int>(op) << " left an output unwritten";
            }
        }
    }
}

// Discarded outputs (register -1) are skipped, not written through a bad index.
TEST(ConverterNodes, DiscardedOutputsAreNotWritten) {
    float reg[8] = {0.25f, 0.5f, 0.75f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    const int32_t params[1] = {0};
    const int32_t in[1] = {0};
    const int32_t out[3] = {-1, 4, -1};
    OpArgs a{params, in, out, reg};
    ASSERT_TRUE(run_converter_op(ShaderOp::separate_color, a, nullptr));
    EXPECT_EQ(reg[4], 0.5f);
    EXPECT_EQ(reg[3], 0.0f);
    EXPECT_EQ(reg[5], 0.0f);
}

}  // namespace
}  // namespace ps
