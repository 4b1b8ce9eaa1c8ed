// Shader programs: the encoding's validation, constant folding, and the ops that read the shading point
// (coordinates, attributes, images, Bump, Normal Map), checked against values worked out by hand from Cycles
// 3.4's definitions. The procedural texture and converter ops have their own tests against Cycles' renders
// (test_texture_nodes.cpp, test_converter_nodes.cpp).
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "photonsplat/errors.h"
#include "photonsplat/material_program.h"
#include "photonsplat/render.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/shading.h"
#include "test_scenes.h"

using namespace ps;

namespace {

// The filter width param of an op that reads the shading point: a float's bits (OpArgs::param_float).
int32_t width_bits(float width) {
    int32_t bits;
    std::memcpy(&bits, &width, sizeof bits);
    return bits;
}
const int32_t kUnitWidth = width_bits(1.0f);  // Blender 3.x's bump offset: one whole differential

// Writes programs the way the add-on's compiler does: registers for constants, one instruction per node.
struct ProgramWriter {
    ShaderProgram p;
    int constant(float v) {
        p.registers.push_back(v);
        return static_cast<int>(p.registers.size()) - 1;
    }
    int vec(const glm::vec3& v) {
        const int r = constant(v.x);
        constant(v.y);
        constant(v.z);
        return r;
    }
    int scratch(int n) {
        const int r = static_cast<int>(p.registers.size());
        p.registers.resize(p.registers.size() + n, 0.0f);
        return r;
    }
    // Outputs: -1 discards; otherwise allocated here, by the op's types.
    std::vector<int> op(ShaderOp op, std::vector<int> params, std::vector<int> in, std::vector<bool> used = {}) {
        const ShaderOpInfo& info = shader_op_info(op);
        const int n_out = static_cast<int>(std::strlen(info.outputs));
        std::vector<int> out;
        for (int o = 0; o < n_out; ++o) {
            const bool keep = used.empty() || used[o];
            out.push_back(keep ? scratch(info.outputs[o] == 'v' ? 3 : 1) : -1);
        }
        p.code.push_back(static_cast<int32_t>(op));
        p.code.push_back(static_cast<int32_t>(params.size()));
        p.code.push_back(static_cast<int32_t>(in.size()));
        p.code.push_back(n_out);
        p.code.insert(p.code.end(), params.begin(), params.end());
        p.code.insert(p.code.end(), in.begin(), in.end());
        p.code.insert(p.code.end(), out.begin(), out.end());
        return out;
    }
    void output(ProgramTarget target, int index, int reg) { p.outputs.push_back({target, index, reg}); }
};

Material diffuse_closures(const std::string& name) {
    Material m;
    m.name = name;
    m.kind = MaterialKind::closures;
    Closure c;
    c.kind = ClosureKind::diffuse;
    c.color = glm::vec3(0.8f);
    m.closures.push_back(c);
    return m;
}

// The unit quad in z = 0 with UVs (0,0)..(1,1) over (-0.5,-0.5)..(0.5,0.5), and a per-vertex colour attribute.
uint32_t add_quad(Scene& scene, uint32_t material, uint32_t colour_id) {
    static const float v[12] = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    static const float colour[16] = {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 0.5f};
    static const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    const int32_t m[2] = {static_cast<int32_t>(material), static_cast<int32_t>(material)};
    MeshInput mesh = test::mesh_input("quad", v, 4, t, 2, m);
    mesh.uvs = uv;
    mesh.attributes.push_back({colour_id, colour, 4, false});
    return scene.add_mesh_data(mesh);
}

Ray down_at(float x, float y) { return Ray{{x, y, 5.0f}, {0.0f, 0.0f, -1.0f}}; }

SurfacePoint hit_at(const Scene& scene, float x, float y) {
    Hit hit;
    const Ray ray = down_at(x, y);
    EXPECT_TRUE(scene.ray_tracer().intersect(ray, 0.0f, 100.0f, hit));
    return surface_at(scene, ray, hit);
}

glm::vec3 albedo_at(const Scene& scene, float x, float y) {
    return shade(scene, hit_at(scene, x, y), glm::vec3(0.0f, 0.0f, 1.0f)).lambert;
}

void expect_vec_near(const glm::vec3& a, const glm::vec3& b, float tolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

}  // namespace

TEST(ShaderProgram, OpTableIsConsistent) {
    ASSERT_GT(shader_op_count(), 50);
    for (int i = 0; i < shader_op_count(); ++i) {
        const ShaderOpInfo& info = shader_op_info(static_cast<ShaderOp>(i));
        EXPECT_GT(std::strlen(info.name), 0u);
        EXPECT_GE(info.params, 0);
        for (const char* t : {info.inputs, info.outputs})
            for (const char* c = t; *c; ++c) EXPECT_TRUE(*c == 'f' || *c == 'v') << info.name;
        EXPECT_GT(std::strlen(info.outputs), 0u) << info.name;
    }
    EXPECT_STREQ(shader_op_info(ShaderOp::image_texture).name, "image_texture");
}

TEST(ShaderProgram, ValidationNamesWhatIsWrong) {
    const auto rejects = [](ShaderProgram p, int closures) {
        EXPECT_THROW(validate(p, closures, "material 'm'.program"), InvalidInput);
    };
    ProgramWriter w;
    const int a = w.constant(1.0f);
    const auto out = w.op(ShaderOp::copy_float, {}, {a});
    w.output(ProgramTarget::closure_roughness, 0, out[0]);
    EXPECT_NO_THROW(validate(w.p, 1, "p"));
    rejects(w.p, 0);  // output for a closure the material does not have
    ShaderProgram bad = w.p;
    bad.code[0] = 9999;
    rejects(bad, 1);  // unknown op
    bad = w.p;
    bad.code[2] = 2;
    rejects(bad, 1);  // wrong input count
    bad = w.p;
    bad.code[4] = 100;
    rejects(bad, 1);  // input register out of range
    bad = w.p;
    bad.code.pop_back();
    rejects(bad, 1);  // truncated
    bad = w.p;
    bad.registers[0] = std::nanf("");
    rejects(bad, 1);
    bad = w.p;
    bad.outputs[0].register_ = 1000;
    rejects(bad, 1);
    bad = w.p;
    bad.outputs[0] = {ProgramTarget::emission, 0, out[0]};  // a vector output past the last register
    rejects(bad, 1);
    ProgramWriter ramp;
    ramp.op(ShaderOp::color_ramp, {0, 4, 1}, {ramp.constant(0.5f)});
    ramp.p.tables.assign(15, 0.0f);  // 4 entries need 16 floats
    rejects(ramp.p, 1);

    // The scene refuses a program that names a texture it does not have.
    Scene scene;
    ProgramWriter img;
    const auto c = img.op(ShaderOp::image_texture, {3, 0, 0, 0, 0}, {img.vec(glm::vec3(0.5f)), img.constant(0.0f)});
    img.output(ProgramTarget::closure_color, 0, c[0]);
    Material m = diffuse_closures("image");
    m.program = img.p;
    EXPECT_THROW(scene.add_material(m), InvalidInput);
}

TEST(ShaderProgram, ConstantInputsFoldIntoTheClosures) {
    Scene scene;
    ProgramWriter w;
    const auto rgb = w.op(ShaderOp::combine_xyz, {}, {w.constant(0.2f), w.constant(0.4f), w.constant(0.6f)});
    const auto grey = w.op(ShaderOp::color_to_float, {}, {rgb[0]});
    w.op(ShaderOp::texture_coordinate, {0, -1, kUnitWidth}, {});  // read by nothing: dropped
    w.output(ProgramTarget::closure_color, 0, rgb[0]);
    w.output(ProgramTarget::closure_roughness, 0, grey[0]);
    Material m = diffuse_closures("folded");
    m.program = w.p;
    const Material& added = scene.materials()[scene.add_material(m)];
    EXPECT_FALSE(added.programmed);
    EXPECT_TRUE(added.program.empty());
    expect_vec_near(added.closures[0].color, glm::vec3(0.2f, 0.4f, 0.6f), 1e-6f);
    // Cycles 3.4's luminance for Blender's default colour configuration.
    EXPECT_NEAR(added.closures[0].roughness, 0.212673f * 0.2f + 0.715153f * 0.4f + 0.0721755f * 0.6f, 1e-5f);
    EXPECT_TRUE(added.directional);  // an Oren–Nayar roughness came out of the program
}

TEST(ShaderProgram, CoordinatesAndAttributesAtTheHit) {
    Scene scene;
    const uint32_t colour_id = scene.attribute_id("Col");
    EXPECT_EQ(scene.attribute_id("Col"), colour_id);
    ProgramWriter uv_w;
    const auto tc = uv_w.op(ShaderOp::texture_coordinate, {0, -1, kUnitWidth}, {}, {false, false, true, false, false, false, false});
    uv_w.output(ProgramTarget::closure_color, 0, tc[2]);
    Material uv_m = diffuse_closures("uv");
    uv_m.program = uv_w.p;
    const uint32_t uv_material = scene.add_material(uv_m);
    ASSERT_TRUE(scene.materials()[uv_material].programmed);
    ASSERT_TRUE(scene.materials()[uv_material].lambert_only);

    ProgramWriter gen_w;
    const auto gen = gen_w.op(ShaderOp::texture_coordinate, {0, -1, kUnitWidth}, {}, {true, false, false, false, false, false, false});
    gen_w.output(ProgramTarget::emission, 0, gen[0]);
    Material gen_m = diffuse_closures("generated");
    gen_m.program = gen_w.p;
    const uint32_t gen_material = scene.add_material(gen_m);

    ProgramWriter attr_w;
    const auto attr = attr_w.op(ShaderOp::attribute, {0, static_cast<int>(colour_id), kUnitWidth}, {});
    attr_w.output(ProgramTarget::closure_color, 0, attr[0]);
    attr_w.output(ProgramTarget::emission, 0, attr_w.op(ShaderOp::float_to_vector, {}, {attr[3]})[0]);
    Material attr_m = diffuse_closures("attribute");
    attr_m.program = attr_w.p;
    const uint32_t attr_material = scene.add_material(attr_m);

    scene.add_instance(add_quad(scene, uv_material, colour_id), glm::mat4(1.0f));
    scene.add_instance(add_quad(scene, gen_material, colour_id), glm::translate(glm::mat4(1.0f), glm::vec3(3, 0, 0)));
    scene.add_instance(add_quad(scene, attr_material, colour_id), glm::translate(glm::mat4(1.0f), glm::vec3(6, 0, 0)));

    expect_vec_near(albedo_at(scene, 0.2f, -0.3f), glm::vec3(0.7f, 0.2f, 0.0f), 1e-5f);
    // The lambert_only path of the stages reads the same values.
    const SurfacePoint s = hit_at(scene, 0.2f, -0.3f);
    expect_vec_near(lambert_albedo(scene, s, glm::vec3(0, 0, 1)), glm::vec3(0.7f, 0.2f, 0.0f), 1e-5f);
    // Generated: the box's texture space, z of a flat mesh at 0.5 (its zero extent counts as 1).
    const SurfacePoint g = hit_at(scene, 3.25f, 0.25f);
    expect_vec_near(emission_at(scene, g, glm::vec3(0, 0, 1)), glm::vec3(0.75f, 0.75f, 0.5f), 1e-5f);
    // Vertex colours: the corner (-0.5, 0.5) is white with alpha 0.5, (0.5, 0.5) blue, (0.5, -0.5) green.
    const SurfacePoint corner = hit_at(scene, 5.5001f, 0.4999f);
    expect_vec_near(albedo_at(scene, 5.5001f, 0.4999f), glm::vec3(1.0f), 1e-3f);
    expect_vec_near(emission_at(scene, corner, glm::vec3(0, 0, 1)), glm::vec3(0.5f), 1e-3f);
    expect_vec_near(albedo_at(scene, 6.4999f, 0.4999f), glm::vec3(0.0f, 0.0f, 1.0f), 1e-3f);
    expect_vec_near(albedo_at(scene, 6.4999f, -0.4999f), glm::vec3(0.0f, 1.0f, 0.0f), 1e-3f);
}

TEST(ShaderProgram, ImageLookupsFollowCycles) {
    // 4 × 1: grey levels 0, 0.25, 0.5, 1 with alpha 1, 1, 0.5, 0 in the last two.
    const float pixels[16] = {0, 0, 0, 1, 0.25f, 0.25f, 0.25f, 1, 0.5f, 0.5f, 0.5f, 0.5f, 1, 1, 1, 0};
    const Texture t("ramp", pixels, 4, 1, 4, ColorSpace::linear);
    const auto grey = [&](float u, TextureInterpolation i, TextureExtension e, TextureAlpha a = TextureAlpha::channel_packed) {
        return t.sample(u, 0.5f, i, e, a);
    };
    EXPECT_FLOAT_EQ(grey(0.3f, TextureInterpolation::closest, TextureExtension::repeat).x, 0.25f);
    EXPECT_FLOAT_EQ(grey(0.25f, TextureInterpolation::linear, TextureExtension::repeat).x, 0.125f);  // between centres
    EXPECT_FLOAT_EQ(grey(0.0f, TextureInterpolation::linear, TextureExtension::repeat).x, 0.5f);     // wraps: 0 and 1
    EXPECT_FLOAT_EQ(grey(0.0f, TextureInterpolation::linear, TextureExtension::extend).x, 0.0f);
    EXPECT_FLOAT_EQ(grey(1.2f, TextureInterpolation::closest, TextureExtension::clip).x, 0.0f);
    EXPECT_FLOAT_EQ(grey(1.2f, TextureInterpolation::closest, TextureExtension::clip).w, 0.0f);
    EXPECT_FLOAT_EQ(grey(0.0f, TextureInterpolation::linear, TextureExtension::clip).x, 0.0f);       // half outside
    EXPECT_FLOAT_EQ(grey(-0.3f, TextureInterpolation::closest, TextureExtension::mirror).x, 0.25f);
    // Cubic: the B-spline at a texel centre is (1 4 1)/6 of its neighbours.
    EXPECT_NEAR(grey(0.375f, TextureInterpolation::cubic, TextureExtension::extend).x,
                (0.0f + 4.0f * 0.25f + 0.5f) / 6.0f, 1e-6f);
    // Alpha: interpolated associated, then divided back (Cycles' unassociated output), or left associated.
    const glm::vec4 mid = grey(0.5f, TextureInterpolation::linear, TextureExtension::repeat, TextureAlpha::unassociated);
    EXPECT_NEAR(mid.w, 0.75f, 1e-6f);
    EXPECT_NEAR(mid.x, (0.5f * 0.25f + 0.5f * 0.25f) / 0.75f, 1e-6f);
    const glm::vec4 assoc = grey(0.5f, TextureInterpolation::linear, TextureExtension::repeat, TextureAlpha::associated);
    EXPECT_NEAR(assoc.x, 0.5f * 0.25f + 0.5f * 0.25f, 1e-6f);
    EXPECT_FLOAT_EQ(grey(0.875f, TextureInterpolation::closest, TextureExtension::repeat, TextureAlpha::unassociated).x, 0.0f);
    // Non-finite coordinates give transparent black, never a crash.
    EXPECT_EQ(t.sample(std::nanf(""), 0.5f, TextureInterpolation::cubic, TextureExtension::repeat, TextureAlpha::unassociated),
              glm::vec4(0.0f));
    EXPECT_TRUE(std::isfinite(grey(1e30f, TextureInterpolation::cubic, TextureExtension::mirror).x));
}

TEST(ShaderProgram, BumpTiltsTheNormalAgainstTheHeightsGradient) {
    // Height = (x + y + z) / 3 in object space, distance 0.3: N' = normalize(N − 0.3 ∇h) = normalize(−0.1, −0.1, 1).
    Scene scene;
    ProgramWriter w;
    std::vector<int> heights;
    for (int k = 0; k < 3; ++k) {
        const auto tc = w.op(ShaderOp::texture_coordinate, {k, -1, kUnitWidth}, {}, {false, false, false, true, false, false, false});
        heights.push_back(w.op(ShaderOp::vector_to_float, {}, {tc[3]})[0]);
    }
    const auto n = w.op(ShaderOp::bump, {0, 0, kUnitWidth},
                        {w.constant(1.0f), w.constant(0.3f), heights[0], heights[1], heights[2], w.vec(glm::vec3(0.0f))});
    w.output(ProgramTarget::normal, 0, n[0]);
    Material m = diffuse_closures("bumped");
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    ASSERT_TRUE(scene.materials()[material].program_normal);
    scene.add_instance(add_quad(scene, material, scene.attribute_id("Col")), glm::mat4(1.0f));
    const SurfacePoint s = hit_at(scene, 0.1f, 0.2f);
    expect_vec_near(s.shading_normal, glm::normalize(glm::vec3(-0.1f, -0.1f, 1.0f)), 1e-4f);
    expect_vec_near(s.smooth_normal, glm::vec3(0, 0, 1), 1e-6f);
    expect_vec_near(shade(scene, s, glm::vec3(0, 0, 1)).n, s.shading_normal, 1e-6f);
}


// The unit quad under a Bump of distance 0.3 and filter width `width` whose Height is an object-space function of
// the position: its coordinates' mean (linear), or their squares' mean (quadratic).
void add_bumped_quad(Scene& scene, float width, bool quadratic) {
    ProgramWriter w;
    std::vector<int> heights;
    for (int k = 0; k < 3; ++k) {
        const auto tc = w.op(ShaderOp::texture_coordinate, {k, -1, width_bits(width)}, {},
                             {false, false, false, true, false, false, false});
        int height = tc[3];
        if (quadratic)
            height = w.op(ShaderOp::vector_math, {2}, {tc[3], tc[3], w.vec(glm::vec3(0.0f)), w.constant(1.0f)},
                          {true, false})[0];
        heights.push_back(w.op(ShaderOp::vector_to_float, {}, {height})[0]);
    }
    const auto n = w.op(ShaderOp::bump, {0, 0, width_bits(width)},
                        {w.constant(1.0f), w.constant(0.3f), heights[0], heights[1], heights[2], w.vec(glm::vec3(0.0f))});
    w.output(ProgramTarget::normal, 0, n[0]);
    Material m = diffuse_closures("bumped");
    m.program = w.p;
    scene.add_instance(add_quad(scene, scene.add_material(m), scene.attribute_id("Col")), glm::mat4(1.0f));
}

TEST(ShaderProgram, BumpSamplesItsHeightAFilterWidthOfDifferentialsAway) {
    // Height = (x² + y²) / 3 in object space, distance 0.3, under an orthographic camera whose pixel is dP = 0.2
    // across. Cycles moves the height's samples width × dP along its two orthonormals a, b about N = z
    // (a = (1, −1, 0)/√2, b = N × a): a quadratic's difference over a step δ is ∇h·δ + |δ|²/3, so the gradient
    // the Bump sees is ∇h + (width dP / 3)(a + b), with a + b = (√2, 0, 0). Blender 3.x's step is width 1; 4.x's
    // Filter Width defaults to 0.1, which brings the normal near the height's true gradient.
    const float dP = 0.2f, x = 0.1f, y = 0.2f;
    for (const float width : {1.0f, 0.5f, 0.1f}) {
        Scene scene;
        ShaderCamera camera;
        camera.orthographic = true;
        camera.pixel_spread = dP;
        scene.set_shader_camera(camera);
        add_bumped_quad(scene, width, true);
        const glm::vec3 seen_gradient =
            glm::vec3(2.0f * x / 3.0f, 2.0f * y / 3.0f, 0.0f) + (width * dP / 3.0f) * glm::vec3(std::sqrt(2.0f), 0, 0);
        SCOPED_TRACE(width);
        expect_vec_near(hit_at(scene, x, y).shading_normal,
                        glm::normalize(glm::vec3(0.0f, 0.0f, 1.0f) - 0.3f * seen_gradient), 1e-4f);
    }
}

TEST(ShaderProgram, BumpOfFilterWidthZeroOrNotANumberKeepsItsNormal) {
    // No step: the three heights are one, and the Bump hands its input normal on (Cycles' is_zero branch).
    for (const float width : {0.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        Scene scene;
        add_bumped_quad(scene, width, false);
        SCOPED_TRACE(width);
        expect_vec_near(hit_at(scene, 0.1f, 0.2f).shading_normal, glm::vec3(0.0f, 0.0f, 1.0f), 1e-6f);
    }
}

TEST(ShaderProgram, TangentSpaceNormalMapFollowsTheUvs) {
    Scene scene;
    ProgramWriter w;
    const auto n = w.op(ShaderOp::normal_map, {0, -1, -1}, {w.constant(1.0f), w.vec(glm::vec3(0.75f, 0.5f, 1.0f))});
    w.output(ProgramTarget::normal, 0, n[0]);
    Material m = diffuse_closures("normal mapped");
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    scene.add_instance(add_quad(scene, material, scene.attribute_id("Col")), glm::mat4(1.0f));
    // (0.75, 0.5, 1) → (0.5, 0, 1) in (tangent = +u = +x, bitangent = +v = +y, normal).
    expect_vec_near(hit_at(scene, 0.1f, 0.1f).shading_normal, glm::normalize(glm::vec3(0.5f, 0.0f, 1.0f)), 1e-5f);
}

TEST(ShaderProgram, TangentSpaceNormalMapReadsMikkTSpaceTangentsWhereGiven) {
    // A per-corner tangent (0, 1, 0) with bitangent sign −1, as Blender's calc_tangents gives it: the bitangent is
    // −(n × t) = +x, so (0.75, 0.5, 1) → 0.5 t + 0 b + n = (0, 0.5, 1).
    Scene scene;
    const uint32_t tangent_id = scene.attribute_id("\x01tangent:");
    ProgramWriter w;
    const auto n = w.op(ShaderOp::normal_map, {0, -1, static_cast<int>(tangent_id)},
                        {w.constant(1.0f), w.vec(glm::vec3(0.75f, 0.5f, 1.0f))});
    w.output(ProgramTarget::normal, 0, n[0]);
    Material m = diffuse_closures("mikktspace");
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    static const float v[12] = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    static const float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    static const float tangent[16] = {0, 1, 0, -1, 0, 1, 0, -1, 0, 1, 0, -1, 0, 1, 0, -1};
    static const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    const int32_t ids[2] = {static_cast<int32_t>(material), static_cast<int32_t>(material)};
    MeshInput mesh = test::mesh_input("quad", v, 4, t, 2, ids);
    mesh.uvs = uv;
    mesh.attributes.push_back({tangent_id, tangent, 4, false});
    scene.add_instance(scene.add_mesh_data(mesh), glm::mat4(1.0f));
    expect_vec_near(hit_at(scene, 0.1f, 0.1f).shading_normal, glm::normalize(glm::vec3(0.0f, 0.5f, 1.0f)), 1e-5f);
}

TEST(ShaderProgram, ProgrammedEmissionIsSeenAndSampledPerTriangle) {
    Scene scene;
    ProgramWriter w;
    const auto tc = w.op(ShaderOp::texture_coordinate, {0, -1, kUnitWidth}, {}, {false, false, true, false, false, false, false});
    w.output(ProgramTarget::emission, 0, tc[2]);
    Material m = diffuse_closures("lamp");
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    EXPECT_TRUE(scene.materials()[material].program_emission);
    scene.add_instance(add_quad(scene, material, scene.attribute_id("Col")), glm::mat4(1.0f));
    expect_vec_near(emission_at(scene, hit_at(scene, 0.3f, -0.4f), glm::vec3(0, 0, 1)), glm::vec3(0.8f, 0.1f, 0.0f),
                    1e-5f);
}

TEST(ShaderProgram, RenderedEmissionShowsWindowCoordinatesAndCameraDepth) {
    // A plane filling an orthographic view, emitting (window x, window y, view z depth): the frame must show
    // each pixel's centre in [0, 1]² (window coordinates, y up) and the distance to the camera (4).
    Scene scene;
    ProgramWriter w;
    const auto tc = w.op(ShaderOp::texture_coordinate, {0, -1, kUnitWidth}, {}, {false, false, false, false, false, true, false});
    const auto cam = w.op(ShaderOp::camera_data, {}, {}, {false, true, false});
    const auto sep = w.op(ShaderOp::combine_xyz, {}, {tc[5], tc[5] + 1, cam[1]});
    w.output(ProgramTarget::emission, 0, sep[0]);
    Material m = diffuse_closures("window");
    m.closures[0].color = glm::vec3(0.0f);
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    scene.add_instance(add_quad(scene, material, scene.attribute_id("Col")), glm::scale(glm::mat4(1.0f), glm::vec3(4.0f)));
    glm::mat4 projection = glm::ortho(-1.0f, 1.0f, -0.5f, 0.5f, 0.1f, 10.0f);
    const Camera camera(glm::dmat4(test::look_at_matrix({0, 0, 4}, {0, 0, 0}, {0, 1, 0})), projection, 8, 4);
    RenderSettings settings;
    settings.photons = 1000;
    RenderControl control;
    const RenderResult r = render(scene, camera, settings, control);
    const std::vector<float>& rgba = r.rgba();
    for (int y = 0; y < 4; ++y)
        for (int px = 0; px < 8; ++px) {
            const float* p = &rgba[4 * (static_cast<size_t>(y) * 8 + px)];
            EXPECT_NEAR(p[0], (px + 0.5f) / 8.0f, 1e-4f);
            EXPECT_NEAR(p[1], 1.0f - (y + 0.5f) / 4.0f, 1e-4f);
            EXPECT_NEAR(p[2], 4.0f, 1e-4f);
        }
}

TEST(ShaderProgram, SrgbImagesInterpolateEncodedAndPremultipliedOnesAreUnassociated) {
    // Cycles keeps 8-bit sRGB images encoded and decodes after interpolating: halfway between black and white is
    // the decoded 0.5 (0.214), not 0.5.
    const float bw[6] = {0, 0, 0, 1, 1, 1};
    const Texture srgb("bw", bw, 2, 1, 3, ColorSpace::srgb);
    EXPECT_NEAR(srgb.sample(0.5f, 0.5f, TextureInterpolation::linear, TextureExtension::extend,
                            TextureAlpha::unassociated).x, 0.21404114f, 1e-6f);
    EXPECT_NEAR(srgb.lookup({0.5f, 0.5f}).x, 0.21404114f, 1e-6f);
    // A premultiplied texel (Blender's float buffers): associated output as given, unassociated divided.
    const float premultiplied[4] = {0.25f, 0.25f, 0.25f, 0.5f};
    const Texture p("p", premultiplied, 1, 1, 4, ColorSpace::linear, true);
    EXPECT_NEAR(p.sample(0.5f, 0.5f, TextureInterpolation::linear, TextureExtension::repeat, TextureAlpha::associated).x,
                0.25f, 1e-6f);
    EXPECT_NEAR(p.sample(0.5f, 0.5f, TextureInterpolation::linear, TextureExtension::repeat, TextureAlpha::unassociated).x,
                0.5f, 1e-6f);
}

TEST(ShaderProgram, BumpedNormalsKeepReflectionsAboveTheSurface) {
    // Cycles' ensure_valid_reflection: a normal tilted so far that the view's mirror direction would go under the
    // surface is tilted back just enough; a normal that reflects fine is left alone.
    const glm::vec3 ng(0, 0, 1);
    const glm::vec3 i = glm::normalize(glm::vec3(1, 0, 0.2f));  // a grazing view from +x
    EXPECT_EQ(ensure_valid_reflection(ng, i, ng), ng);
    const glm::vec3 n = glm::normalize(glm::vec3(-0.8f, 0.0f, 0.6f));  // leaning away from the viewer: R goes down
    ASSERT_LT(glm::dot(ng, 2.0f * glm::dot(n, i) * n - i), 0.0f);
    const glm::vec3 fixed = ensure_valid_reflection(ng, i, n);
    EXPECT_NEAR(glm::length(fixed), 1.0f, 1e-5f);
    const float threshold = std::min(0.9f * glm::dot(ng, i), 0.01f);
    EXPECT_NEAR(glm::dot(ng, 2.0f * glm::dot(fixed, i) * fixed - i), threshold, 1e-4f);
    EXPECT_NEAR(fixed.y, 0.0f, 1e-6f);  // turned in the plane of n and ng only
}

TEST(ShaderProgram, RepeatedRunsAtOnePointFollowTheSceneWhenItChanges) {
    // A point shaded twice in a row reuses the first run (surface_at's normal, then shade's closures); moving the
    // instance in between must not: the scene's revision is part of what the reuse compares.
    Scene scene;
    ProgramWriter w;
    const auto geometry = w.op(ShaderOp::geometry, {0, -1, -1, kUnitWidth}, {}, {true, false, false, false, false, false, false, false, false});
    w.output(ProgramTarget::emission, 0, geometry[0]);
    Material m = diffuse_closures("position");
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    const uint32_t quad = add_quad(scene, material, scene.attribute_id("Col"));
    const uint32_t instance = scene.add_instance(quad, glm::mat4(1.0f));
    const SurfacePoint before = hit_at(scene, 0.1f, 0.2f);
    expect_vec_near(emission_at(scene, before, glm::vec3(0, 0, 1)), glm::vec3(0.1f, 0.2f, 0.0f), 1e-5f);
    expect_vec_near(emission_at(scene, before, glm::vec3(0, 0, 1)), glm::vec3(0.1f, 0.2f, 0.0f), 1e-5f);
    scene.set_instance_transform(instance, glm::dmat4(glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, 1))));
    SurfacePoint moved = before;  // the same triangle and barycentrics, now 1 higher
    moved.position.z += 1.0f;
    expect_vec_near(emission_at(scene, moved, glm::vec3(0, 0, 1)), glm::vec3(0.1f, 0.2f, 1.0f), 1e-5f);
}

TEST(ShaderProgram, RandomProgramsAreRefusedOrRunFinitely) {
    // Hostile programs: every op with random params, registers and tables. Each is either refused with
    // InvalidInput or runs at a hit without crashing (the sanitizer builds run this too); whatever it sets is made
    // finite before use.
    std::mt19937 rng(16);
    Scene scene;
    const float pixels[16] = {0.1f, 0.2f, 0.3f, 1, 0.4f, 0.5f, 0.6f, 0.5f, 0.7f, 0.8f, 0.9f, 0, 1, 1, 1, 1};
    scene.add_texture(Texture("t", pixels, 2, 2, 4, ColorSpace::srgb));
    const uint32_t white = scene.add_material(diffuse_closures("white"));
    scene.add_instance(add_quad(scene, white, scene.attribute_id("Col")), glm::mat4(1.0f));
    std::uniform_int_distribution<int> pick_op(0, shader_op_count() - 1), small(-2, 24), any(0, 63);
    std::uniform_real_distribution<float> value(-1e3f, 1e3f);
    int refused = 0, ran = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        ProgramWriter w;
        for (int r = 0; r < 64; ++r) w.constant(trial % 7 == 0 ? value(rng) * 1e30f : value(rng));
        w.p.tables.resize(any(rng) * 8);
        for (float& t : w.p.tables) t = value(rng);
        const int count = 1 + any(rng) % 6;
        int last = 0;
        for (int k = 0; k < count; ++k) {
            const ShaderOp op = static_cast<ShaderOp>(pick_op(rng));
            const ShaderOpInfo& info = shader_op_info(op);
            std::vector<int> params, in;
            for (int p = 0; p < info.params; ++p) params.push_back(small(rng));
            for (const char* c = info.inputs; *c; ++c) in.push_back(any(rng) % 60);
            const auto out = w.op(op, params, in);
            last = out[0];
        }
        w.output(ProgramTarget::closure_color, 0, last);
        w.output(ProgramTarget::normal, 0, last);
        w.output(ProgramTarget::emission, 0, last);
        Material m = diffuse_closures("random");
        m.program = w.p;
        uint32_t material;
        try {
            material = scene.add_material(m);
        } catch (const InvalidInput&) {
            ++refused;
            continue;
        }
        ++ran;
        const Material& added = scene.materials()[material];
        SurfacePoint s = hit_at(scene, 0.1f, 0.2f);
        s.material = &added;
        const Bsdf b = shade(scene, s, glm::vec3(0, 0, 1));
        EXPECT_TRUE(std::isfinite(b.lambert.x) && std::isfinite(b.n.x)) << "trial " << trial;
        const glm::vec3 e = emission_at(scene, s, glm::vec3(0, 0, 1));
        EXPECT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z)) << "trial " << trial;
    }
    EXPECT_GT(ran, 1000);
    EXPECT_GT(refused, 10);
}

TEST(ShaderProgram, LambertPathKeepsAClosureTextureBesideAProgram) {
    // A Diffuse closure coloured by an image straight in (the closure's texture) whose material also has a
    // program (a Bump normal): the stages' Lambert path must see the textured colour, as shade() does.
    Scene scene;
    const float red[3] = {1.0f, 0.0f, 0.0f};
    const int32_t texture = static_cast<int32_t>(scene.add_texture(Texture("red", red, 1, 1, 3, ColorSpace::linear)));
    ProgramWriter w;
    const auto n = w.op(ShaderOp::bump, {0, 0, kUnitWidth}, {w.constant(1.0f), w.constant(0.1f), w.constant(0.0f),
                                                 w.constant(0.0f), w.constant(0.0f), w.vec(glm::vec3(0.0f))});
    w.output(ProgramTarget::normal, 0, n[0]);
    Material m = diffuse_closures("textured and bumped");
    m.closures[0].texture = texture;
    m.program = w.p;
    const uint32_t material = scene.add_material(m);
    ASSERT_TRUE(scene.materials()[material].programmed);
    ASSERT_TRUE(scene.materials()[material].lambert_only);
    scene.add_instance(add_quad(scene, material, scene.attribute_id("Col")), glm::mat4(1.0f));
    const SurfacePoint s = hit_at(scene, 0.1f, 0.2f);
    expect_vec_near(lambert_albedo(scene, s, glm::vec3(0, 0, 1)), glm::vec3(0.8f, 0.0f, 0.0f), 1e-6f);
    expect_vec_near(shade(scene, s, glm::vec3(0, 0, 1)).lambert, glm::vec3(0.8f, 0.0f, 0.0f), 1e-6f);
}
