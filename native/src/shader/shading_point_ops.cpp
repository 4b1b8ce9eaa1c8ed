// The ops that read the shading point (ShaderGlobals): coordinates, geometry, the object, the ray and the
// camera, and the ops that make a normal (Fresnel and Layer Weight read it; Normal Map and Bump make one).
// Definitions: Cycles 3.4's svm/tex_coord.h, geometry.h, attribute.h, light_path.h, camera.h, fresnel.h,
// bump.h / displace.h, normal.h, vector_transform.h.
//
// A `bump` param of 1 or 2 evaluates the op at the shading point moved by the Bump node's filter width times
// dPdx or dPdy (Cycles' bump_dx / dy variants), so that a Bump node's height is known at three points. Blender
// 3.x moves it a whole differential (width 1); from 4.1 the node's Filter Width input (0.1 by default) scales the
// step, and the Bump divides the height's differences by it (svm_node_bump_P_dx, svm_node_set_bump).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include "photonsplat/closures.h"
#include "photonsplat/scene.h"
#include "shader/op_args.h"

namespace ps {

namespace {

glm::vec3 safe_normalize(const glm::vec3& v) {
    const float len = glm::length(v);
    return len > 0.0f && std::isfinite(len) ? v / len : glm::vec3(0.0f);
}

// A Normal input: unconnected sockets hold (0, 0, 0), which Cycles reads as the shading normal.
glm::vec3 input_normal(const ShaderGlobals& g, const glm::vec3& n) {
    const glm::vec3 u = safe_normalize(n);
    return u == glm::vec3(0.0f) ? g.N : u;
}

// Where an op reads the shading point: its `bump` param and the filter width param after it. A width that is
// not a finite number moves nothing.
struct BumpOffset {
    int axis = 0;  // 0 the point itself, 1 along dPdx, 2 along dPdy
    float width = 1.0f;
};

BumpOffset bump_offset(const OpArgs& a, int width_param) {
    const float width = a.param_float(width_param);
    return {a.param(0), std::isfinite(width) ? width : 0.0f};
}

glm::vec3 offset_of(const ShaderGlobals& g, BumpOffset o) {
    return o.width * (o.axis == 1 ? g.dPdx : o.axis == 2 ? g.dPdy : glm::vec3(0.0f));
}

glm::vec2 bary_at(const ShaderGlobals& g, BumpOffset o) {
    return g.bary + o.width * (o.axis == 1 ? g.dbary_dx : o.axis == 2 ? g.dbary_dy : glm::vec2(0.0f));
}

// The object-space position at the bump offset.
glm::vec3 object_point(const ShaderGlobals& g, BumpOffset bump) {
    return g.object_position + g.world_to_object_linear * offset_of(g, bump);
}

// An attribute (or the render UV map, id -1) interpolated at the bump offset's barycentrics; missing: 0.
bool attribute_at(const ShaderGlobals& g, int32_t id, BumpOffset bump, glm::vec4& value) {
    value = glm::vec4(0.0f);
    if (g.mesh == nullptr) return false;
    const glm::vec2 b = bary_at(g, bump);
    const size_t t = g.triangle;
    if (id < 0) {
        if (g.mesh->uvs.empty()) return false;
        const glm::vec2 uv =
            (1.0f - b.x - b.y) * g.mesh->uvs[3 * t] + b.x * g.mesh->uvs[3 * t + 1] + b.y * g.mesh->uvs[3 * t + 2];
        value = glm::vec4(uv, 0.0f, 1.0f);
        return true;
    }
    const MeshData::Attribute* a = g.mesh->attribute(static_cast<uint32_t>(id));
    if (a == nullptr || a->corners.size() < 3 * t + 3) return false;
    value = (1.0f - b.x - b.y) * a->corners[3 * t] + b.x * a->corners[3 * t + 1] + b.y * a->corners[3 * t + 2];
    return true;
}

glm::vec3 generated(const ShaderGlobals& g, BumpOffset bump) {
    if (g.background) return g.P;  // Cycles' background: generated coordinates are the direction
    if (g.mesh == nullptr) return glm::vec3(0.0f);
    const glm::vec3 p = object_point(g, bump);
    glm::vec3 r;
    for (int c = 0; c < 3; ++c) {
        const float size = g.mesh->texspace_size[c];
        r[c] = size != 0.0f ? (p[c] - g.mesh->texspace_location[c]) * (0.5f / size) + 0.5f : 0.5f;
    }
    return r;
}

glm::vec3 transform_point(const glm::mat4& m, const glm::vec3& p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

glm::vec3 object_normal(const ShaderGlobals& g, const glm::vec3& n_world) {
    return safe_normalize(glm::transpose(g.object_to_world_linear) * n_world);
}
glm::vec3 world_normal(const ShaderGlobals& g, const glm::vec3& n_object) {
    return safe_normalize(glm::transpose(g.world_to_object_linear) * n_object);
}

// Normal Map in tangent space. Cycles reads a MikkTSpace tangent attribute; we use the triangle's own dP/du (from
// its corners' UVs), made perpendicular to the normal, with the handedness of its dP/dv: the same on flat UV
// layouts, smoothed by neither across triangles.
glm::vec3 tangent_space_normal(const ShaderGlobals& g, int32_t uv_id, const glm::vec3& color) {
    if (g.mesh == nullptr) return g.N;
    const size_t t = g.triangle;
    glm::vec2 uv[3];
    if (uv_id < 0) {
        if (g.mesh->uvs.empty()) return g.N;
        for (int c = 0; c < 3; ++c) uv[c] = g.mesh->uvs[3 * t + c];
    } else {
        const MeshData::Attribute* a = g.mesh->attribute(static_cast<uint32_t>(uv_id));
        if (a == nullptr || a->corners.size() < 3 * t + 3) return g.N;
        for (int c = 0; c < 3; ++c) uv[c] = glm::vec2(a->corners[3 * t + c]);
    }
    const glm::vec3 p0 = g.mesh->positions[g.mesh->indices[3 * t]];
    const glm::vec3 e1 = g.mesh->positions[g.mesh->indices[3 * t + 1]] - p0;
    const glm::vec3 e2 = g.mesh->positions[g.mesh->indices[3 * t + 2]] - p0;
    const glm::vec2 d1 = uv[1] - uv[0], d2 = uv[2] - uv[0];
    const float det = d1.x * d2.y - d1.y * d2.x;
    if (!(std::fabs(det) > 0.0f)) return g.N;
    const glm::vec3 dpdu = (d2.y * e1 - d1.y * e2) / det;
    const glm::vec3 dpdv = (-d2.x * e1 + d1.x * e2) / det;
    // The interpolated normal in object space, on the front side (Cycles flips back to the front here).
    glm::vec3 normal = object_normal(g, g.backfacing ? -g.N : g.N);
    glm::vec3 tangent = safe_normalize(dpdu - normal * glm::dot(normal, dpdu));
    if (tangent == glm::vec3(0.0f)) return g.N;
    const float sign = glm::dot(glm::cross(normal, tangent), dpdv) < 0.0f ? -1.0f : 1.0f;
    const glm::vec3 b = sign * glm::cross(normal, tangent);
    const glm::vec3 n = safe_normalize(color.x * tangent + color.y * b + color.z * normal);
    return world_normal(g, n);
}

// Normal Map in tangent space as Cycles does it, from the mesh's MikkTSpace tangent and bitangent sign (a
// per-corner attribute the add-on takes from Blender's Mesh.calc_tangents), interpolated at the hit, with the
// interpolated (unnormalised) object-space normal; false when the mesh has no such attribute.
bool mikktspace_normal(const ShaderGlobals& g, int32_t tangent_id, const glm::vec3& color, glm::vec3& out) {
    glm::vec4 t;
    if (tangent_id < 0 || !attribute_at(g, tangent_id, BumpOffset{}, t)) return false;
    const glm::vec2 b = g.bary;
    const size_t tri = g.triangle;
    glm::vec3 normal;
    if (!g.mesh->normals.empty()) {
        normal = (1.0f - b.x - b.y) * g.mesh->corner_normal(tri, 0) + b.x * g.mesh->corner_normal(tri, 1) +
                 b.y * g.mesh->corner_normal(tri, 2);
    } else {
        normal = object_normal(g, g.backfacing ? -g.Ng : g.Ng);  // the front face's geometric normal
    }
    const glm::vec3 tangent(t);
    const glm::vec3 bitangent = t.w * glm::cross(normal, tangent);
    const glm::vec3 n = safe_normalize(color.x * tangent + color.y * bitangent + color.z * normal);
    out = world_normal(g, n);
    return true;
}

glm::vec3 normal_map(const ShaderGlobals& g, int space, int32_t uv_id, int32_t tangent_id, float strength,
                     glm::vec3 color) {
    color = 2.0f * (color - 0.5f);
    glm::vec3 n;
    if (space == 0) {
        if (!mikktspace_normal(g, tangent_id, color, n)) n = tangent_space_normal(g, uv_id, color);
        if (g.backfacing) n = -n;
    } else {
        if (space == 3 || space == 4) {  // Blender's own object / world convention
            color.y = -color.y;
            color.z = -color.z;
        }
        n = (space == 1 || space == 3) ? world_normal(g, color) : safe_normalize(color);
        if (g.backfacing) n = -n;
    }
    if (strength != 1.0f) n = safe_normalize(g.N + (n - g.N) * std::max(strength, 0.0f));
    if (n == glm::vec3(0.0f)) n = g.N;
    return n;
}

// Cycles' Bump: the height's surface gradient from three samples `width` differentials apart (Mikkelsen's
// method). The height's differences are over width × dP, so the determinant is weighed by width to match.
glm::vec3 bump(const ShaderGlobals& g, bool invert, float width, const glm::vec3& normal_in, float strength,
               float distance, float h_c, float h_x, float h_y) {
    const glm::vec3 rx = glm::cross(g.dPdy, normal_in), ry = glm::cross(normal_in, g.dPdx);
    const float det = glm::dot(g.dPdx, rx);
    const glm::vec3 surfgrad = (h_x - h_c) * rx + (h_y - h_c) * ry;
    const float scale = invert ? -distance : distance;
    strength = std::max(strength, 0.0f);
    const float sign = det > 0.0f ? 1.0f : det < 0.0f ? -1.0f : 0.0f;
    glm::vec3 out = safe_normalize(width * std::fabs(det) * normal_in - scale * sign * surfgrad);
    if (out == glm::vec3(0.0f)) return normal_in;
    out = safe_normalize(strength * out + (1.0f - strength) * normal_in);
    if (out == glm::vec3(0.0f)) out = normal_in;
    return ensure_valid_reflection(g.Ng, g.I, out);
}

glm::vec3 to_world(const ShaderGlobals& g, const ShaderCamera& cam, int type, int from, const glm::vec3& v) {
    if (from == 1) {  // object
        if (type == 1) return g.P + g.object_to_world_linear * (v - g.object_position);
        return type == 2 ? world_normal(g, v) : g.object_to_world_linear * v;
    }
    if (from == 2) {  // camera
        const glm::mat4 camera_to_world = glm::inverse(cam.world_to_camera);
        if (type == 1) return transform_point(camera_to_world, v);
        const glm::vec3 d = glm::mat3(camera_to_world) * v;
        return type == 2 ? safe_normalize(d) : d;
    }
    return v;
}

glm::vec3 from_world(const ShaderGlobals& g, const ShaderCamera& cam, int type, int to, const glm::vec3& v) {
    if (to == 1) {
        if (type == 1) return g.object_position + g.world_to_object_linear * (v - g.P);
        return type == 2 ? object_normal(g, v) : g.world_to_object_linear * v;
    }
    if (to == 2) {
        if (type == 1) return transform_point(cam.world_to_camera, v);
        const glm::vec3 d = glm::mat3(cam.world_to_camera) * v;
        return type == 2 ? safe_normalize(d) : d;
    }
    return v;
}

}  // namespace

bool run_shading_point_op(ShaderOp op, const OpArgs& a, const float* tables, const Scene& scene,
                          const ShaderGlobals& g) {
    const ShaderCamera& cam = scene.shader_camera();
    switch (op) {
        case ShaderOp::texture_coordinate: {
            const BumpOffset bump_at = bump_offset(a, 2);
            const glm::vec3 p = g.P + offset_of(g, bump_at);
            a.set(0, generated(g, bump_at));
            a.set(1, object_normal(g, g.N));
            glm::vec4 uv;
            attribute_at(g, -1, bump_at, uv);
            a.set(2, glm::vec3(uv.x, uv.y, 0.0f));
            if (a.param(1) >= 0) {
                const float* m = tables + a.param(1);
                glm::mat4 world_to_object;
                for (int c = 0; c < 4; ++c)
                    for (int r = 0; r < 4; ++r) world_to_object[c][r] = m[4 * c + r];
                a.set(3, transform_point(world_to_object, p));
            } else {
                a.set(3, object_point(g, bump_at));
            }
            // The background's camera and window coordinates are of the point one unit from the camera along
            // the direction; its reflection coordinate is I.
            const glm::vec3 seen = g.background ? p + cam.position : p;
            a.set(4, transform_point(cam.world_to_camera, seen));
            const glm::vec4 ndc = cam.world_to_ndc * glm::vec4(seen, 1.0f);
            a.set(5, ndc.w != 0.0f ? glm::vec3(ndc.x / ndc.w, ndc.y / ndc.w, 0.0f) : glm::vec3(0.0f));
            a.set(6, g.background ? g.I : 2.0f * glm::dot(g.N, g.I) * g.N - g.I);
            return true;
        }
        case ShaderOp::uv_map: {
            glm::vec4 uv;
            attribute_at(g, a.param(1), bump_offset(a, 2), uv);
            a.set(0, glm::vec3(uv.x, uv.y, 0.0f));
            return true;
        }
        case ShaderOp::attribute: {
            glm::vec4 v;
            attribute_at(g, a.param(1), bump_offset(a, 2), v);
            a.set(0, glm::vec3(v));
            a.set(1, glm::vec3(v));
            a.set(2, (v.x + v.y + v.z) * (1.0f / 3.0f));
            a.set(3, v.w);
            return true;
        }
        case ShaderOp::geometry: {
            const BumpOffset bump_at = bump_offset(a, 3);
            a.set(0, g.P + offset_of(g, bump_at));
            a.set(1, g.N);
            // Cycles' default tangent: about the Z axis through the texture space's centre.
            const glm::vec3 gen = generated(g, BumpOffset{});
            const glm::vec3 radial = world_normal(g, glm::vec3(-(gen.y - 0.5f), gen.x - 0.5f, 0.0f));
            a.set(2, glm::cross(g.N, safe_normalize(glm::cross(radial, g.N))));
            a.set(3, g.Ng);
            a.set(4, g.I);
            const glm::vec2 b = bary_at(g, bump_at);
            a.set(5, glm::vec3(1.0f - b.x - b.y, b.x, 0.0f));
            a.set(6, g.backfacing ? 1.0f : 0.0f);
            // Pointiness (per vertex) and Random Per Island (per corner, equal over a face) are mesh attributes the
            // add-on computes as Cycles' Blender sync does; absent (id -1, or not on this mesh): 0, as Cycles reads a
            // missing attribute.
            for (int k = 0; k < 2; ++k) {
                glm::vec4 v(0.0f);
                if (a.param(1 + k) >= 0) attribute_at(g, a.param(1 + k), bump_at, v);
                a.set(7 + k, v.x);
            }
            return true;
        }
        case ShaderOp::object_info: {
            const Instance* i = g.instance;
            a.set(0, i ? glm::vec3(i->world_translation) : glm::vec3(0.0f));
            a.set(1, i ? glm::vec3(i->color) : glm::vec3(1.0f));
            a.set(2, i ? i->color.w : 1.0f);
            a.set(3, i ? i->pass_index : 0.0f);
            a.set(4, 0.0f);
            a.set(5, i ? i->random : 0.0f);
            return true;
        }
        case ShaderOp::light_path: {
            const bool reflection = g.diffuse_ray || g.glossy_ray || (g.singular_ray && !g.transmission_ray);
            const float values[13] = {g.camera_ray ? 1.0f : 0.0f, g.shadow_ray ? 1.0f : 0.0f,
                                      g.diffuse_ray ? 1.0f : 0.0f, g.glossy_ray ? 1.0f : 0.0f,
                                      g.singular_ray ? 1.0f : 0.0f, reflection && !g.transmission_ray ? 1.0f : 0.0f,
                                      g.transmission_ray ? 1.0f : 0.0f, g.ray_length, g.ray_depth,
                                      g.diffuse_ray ? g.ray_depth : 0.0f, g.glossy_ray ? g.ray_depth : 0.0f, 0.0f,
                                      g.transmission_ray ? g.ray_depth : 0.0f};
            for (int o = 0; o < 13; ++o) a.set(o, values[o]);
            return true;
        }
        case ShaderOp::camera_data: {
            const glm::vec3 v = transform_point(cam.world_to_camera, g.P);
            a.set(0, safe_normalize(v));
            a.set(1, v.z);
            a.set(2, glm::length(v));
            return true;
        }
        case ShaderOp::fresnel: {
            const glm::vec3 n = input_normal(g, a.v(1));
            const float cos_i = glm::dot(g.I, n);
            const float eta = std::max(a.f(0), 1e-5f);
            a.set(0, fresnel_dielectric_cos(cos_i, g.backfacing ? 1.0f / eta : eta));
            return true;
        }
        case ShaderOp::layer_weight: {
            const glm::vec3 n = input_normal(g, a.v(1));
            const float blend = a.f(0);
            const float cos_i = glm::dot(g.I, n);
            const float eta = std::max(1.0f - blend, 1e-5f);
            a.set(0, fresnel_dielectric_cos(cos_i, g.backfacing ? eta : 1.0f / eta));
            float facing = std::fabs(cos_i);
            if (blend != 0.5f) {
                float b = std::clamp(blend, 0.0f, 1.0f - 1e-5f);
                b = b < 0.5f ? 2.0f * b : 0.5f / (1.0f - b);
                facing = std::pow(facing, b);
            }
            a.set(1, 1.0f - facing);
            return true;
        }
        case ShaderOp::normal_map:
            a.set(0, normal_map(g, a.param(0), a.param(1), a.param(2), a.f(0), a.v(1)));
            return true;
        case ShaderOp::bump: {
            const glm::vec3 n_in = a.param(1) ? input_normal(g, a.v(5)) : g.N;
            const float width = a.param_float(2);
            a.set(0, bump(g, a.param(0) != 0, std::isfinite(width) ? width : 0.0f, n_in, a.f(0), a.f(1), a.f(2),
                          a.f(3), a.f(4)));
            return true;
        }
        case ShaderOp::normal: {
            const glm::vec3 direction = safe_normalize(a.v(0));
            a.set(0, direction);
            a.set(1, glm::dot(direction, safe_normalize(a.v(1))));
            return true;
        }
        case ShaderOp::vector_transform: {
            const int type = a.param(0);
            const glm::vec3 world = to_world(g, cam, type, a.param(1), a.v(0));
            a.set(0, from_world(g, cam, type, a.param(2), world));
            return true;
        }
        default: return false;
    }
}

}  // namespace ps
