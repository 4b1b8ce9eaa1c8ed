// The Geometry node's Pointiness and Random Per Island: the disjoint set whose roots Cycles 3.4 hashes
// (mesh_islands.h), and the geometry op reading the two mesh attributes the add-on computes (its params 1 and 2;
// -1: absent, 0 as Cycles reads a missing attribute). Pointiness itself is computed by the add-on (numpy,
// export/mesh.py) and tested in Blender (tests/blender/test_geometry_node.py).
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "photonsplat/errors.h"
#include "photonsplat/material_program.h"
#include "photonsplat/mesh_islands.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/shader_program.h"
#include "photonsplat/shading.h"
#include "test_scenes.h"

using namespace ps;

namespace {

// hash_uint_to_float(k) of Cycles' util/hash.h (lookup3's final mix), worked out independently in Python.
constexpr float kHash0 = 0.5824258327484131f;
constexpr float kHash1 = 0.2923549711704254f;
constexpr float kHash3 = 0.33624267578125f;
constexpr float kHash6 = 0.2978990077972412f;

}  // namespace

TEST(GeometryAttributes, IslandRootsFollowUnionByRankInEdgeOrder) {
    // A tie in rank keeps the first vertex's root: (1, 0) makes 1 the root, (0, 1) would make 0.
    const int32_t first[] = {1, 0, 2, 0};
    EXPECT_EQ(island_roots(3, first, 2), (std::vector<uint32_t>{1, 1, 1}));
    const int32_t second[] = {0, 1, 2, 0};
    EXPECT_EQ(island_roots(3, second, 2), (std::vector<uint32_t>{0, 0, 0}));
    // The higher rank wins whatever the order: {3, 4} (rank 1) absorbs 5 even when 5 comes first.
    const int32_t ranked[] = {3, 4, 5, 4};
    EXPECT_EQ(island_roots(7, ranked, 2), (std::vector<uint32_t>{0, 1, 2, 3, 3, 3, 6}));
    // Two rank-1 trees: the first argument's root stays.
    const int32_t trees[] = {0, 1, 2, 3, 3, 1};
    EXPECT_EQ(island_roots(4, trees, 3), (std::vector<uint32_t>{2, 2, 2, 2}));
    const int32_t bad[] = {0, 4};
    EXPECT_THROW(island_roots(4, bad, 1), InvalidInput);
    EXPECT_TRUE(island_roots(0, nullptr, 0).empty());
}

TEST(GeometryAttributes, RandomPerIslandHashesTheRoot) {
    const int32_t edges[] = {0, 1, 1, 2, 3, 4, 4, 5};
    const std::vector<float> r = random_per_island(7, edges, 4);
    ASSERT_EQ(r.size(), 7u);
    for (int v : {0, 1, 2}) EXPECT_FLOAT_EQ(r[v], kHash0);
    for (int v : {3, 4, 5}) EXPECT_FLOAT_EQ(r[v], kHash3);
    EXPECT_FLOAT_EQ(r[6], kHash6);
    const int32_t swapped[] = {1, 0};
    EXPECT_FLOAT_EQ(random_per_island(2, swapped, 1)[0], kHash1);
}

namespace {

Material emission_of(const std::string& name, const ShaderProgram& program) {
    Material m;
    m.name = name;
    m.kind = MaterialKind::closures;
    Closure c;
    c.kind = ClosureKind::diffuse;
    c.color = glm::vec3(0.8f);
    m.closures.push_back(c);
    m.program = program;
    return m;
}

// A program emitting (pointiness, random per island, 0) from the geometry op with these attribute ids.
ShaderProgram geometry_program(int pointiness_id, int island_id, int bump = 0) {
    ShaderProgram p;
    const ShaderOpInfo& info = shader_op_info(ShaderOp::geometry);
    const int n_out = static_cast<int>(std::strlen(info.outputs));
    p.registers.assign(3, 0.0f);  // 0..2: the emission (pointiness, random, 0)
    const float width = 1.0f;  // the bump offset's filter width, as a float's bits
    int32_t width_bits;
    std::memcpy(&width_bits, &width, sizeof width_bits);
    p.code = {static_cast<int32_t>(ShaderOp::geometry), 4, 0, n_out, bump, pointiness_id, island_id, width_bits};
    for (int o = 0; o < n_out; ++o) p.code.push_back(o == 7 ? 0 : o == 8 ? 1 : -1);
    p.outputs.push_back({ProgramTarget::emission, 0, 0});
    return p;
}

// The unit quad in z = 0 with a per-vertex pointiness and a per-corner island value (equal over each triangle).
uint32_t add_quad(Scene& scene, uint32_t material, uint32_t pointiness_id, uint32_t island_id) {
    static const float v[12] = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    static const float pointiness[4] = {0.2f, 0.4f, 0.6f, 0.8f};
    static const float island[6] = {0.25f, 0.25f, 0.25f, 0.75f, 0.75f, 0.75f};
    static const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    const int32_t m[2] = {static_cast<int32_t>(material), static_cast<int32_t>(material)};
    MeshInput mesh = test::mesh_input("quad", v, 4, t, 2, m);
    mesh.attributes.push_back({pointiness_id, pointiness, 1, false});
    mesh.attributes.push_back({island_id, island, 1, true});
    return scene.add_mesh_data(mesh);
}

glm::vec3 emission_seen(const Scene& scene, float x, float y) {
    Hit hit;
    const Ray ray{{x, y, 5.0f}, {0.0f, 0.0f, -1.0f}};
    EXPECT_TRUE(scene.ray_tracer().intersect(ray, 0.0f, 100.0f, hit));
    return emission_at(scene, surface_at(scene, ray, hit), glm::vec3(0.0f, 0.0f, 1.0f));
}

}  // namespace

TEST(GeometryAttributes, GeometryOpReadsPointinessAndIslandAttributes) {
    Scene scene;
    const uint32_t pointiness_id = scene.attribute_id("\x01pointiness");
    const uint32_t island_id = scene.attribute_id("\x01random_per_island");
    const uint32_t reads = scene.add_material(
        emission_of("reads", geometry_program(static_cast<int>(pointiness_id), static_cast<int>(island_id))));
    const uint32_t absent = scene.add_material(emission_of("absent", geometry_program(-1, -1)));
    // An id the mesh has no attribute for: 0 as well (Cycles' missing attribute).
    const uint32_t other = scene.attribute_id("not on the mesh");
    const uint32_t missing =
        scene.add_material(emission_of("missing", geometry_program(static_cast<int>(other), static_cast<int>(other))));
    scene.add_instance(add_quad(scene, reads, pointiness_id, island_id), glm::mat4(1.0f));
    scene.add_instance(add_quad(scene, absent, pointiness_id, island_id),
                       glm::translate(glm::mat4(1.0f), glm::vec3(3, 0, 0)));
    scene.add_instance(add_quad(scene, missing, pointiness_id, island_id),
                       glm::translate(glm::mat4(1.0f), glm::vec3(6, 0, 0)));
    ASSERT_TRUE(scene.materials()[reads].programmed);

    // Pointiness interpolates the vertices' values; the island value is the triangle's, unblended.
    const glm::vec3 near_v1 = emission_seen(scene, 0.4999f, -0.4999f);
    EXPECT_NEAR(near_v1.x, 0.4f, 1e-3f);
    EXPECT_NEAR(near_v1.y, 0.25f, 1e-6f);
    const glm::vec3 centre_t0 = emission_seen(scene, 0.2f, -0.3f);   // bary of (v0, v1, v2): 0.3, 0.5, 0.2
    EXPECT_NEAR(centre_t0.x, 0.3f * 0.2f + 0.5f * 0.4f + 0.2f * 0.6f, 1e-5f);
    EXPECT_NEAR(centre_t0.y, 0.25f, 1e-6f);
    const glm::vec3 in_t1 = emission_seen(scene, -0.3f, 0.2f);
    EXPECT_NEAR(in_t1.y, 0.75f, 1e-6f);
    EXPECT_EQ(emission_seen(scene, 3.2f, -0.3f), glm::vec3(0.0f));
    EXPECT_EQ(emission_seen(scene, 6.2f, -0.3f), glm::vec3(0.0f));
}

TEST(GeometryAttributes, GeometryOpTakesFourParams) {
    EXPECT_EQ(shader_op_info(ShaderOp::geometry).params, 4);
    ShaderProgram old;
    const ShaderOpInfo& info = shader_op_info(ShaderOp::geometry);
    const int n_out = static_cast<int>(std::strlen(info.outputs));
    old.registers.assign(3, 0.0f);
    old.code = {static_cast<int32_t>(ShaderOp::geometry), 1, 0, n_out, 0};
    for (int o = 0; o < n_out; ++o) old.code.push_back(o == 7 ? 0 : -1);
    old.outputs.push_back({ProgramTarget::emission, 0, 0});
    EXPECT_THROW(validate(old, 1, "material"), InvalidInput);
}
