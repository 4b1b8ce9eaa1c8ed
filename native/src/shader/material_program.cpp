#include "photonsplat/material_program.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "photonsplat/ray_tracer.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {

// Cycles' make_orthonormals: the two directions about n that its compact differentials use.
void cycles_orthonormals(const glm::vec3& n, glm::vec3& a, glm::vec3& b) {
    if (n.x != n.y || n.x != n.z)
        a = glm::vec3(n.z - n.y, n.x - n.z, n.y - n.x);
    else
        a = glm::vec3(n.z - n.y, n.x + n.z, -n.y - n.x);
    a = glm::normalize(a);
    b = glm::cross(n, a);
}

// The register file of one run: on the stack for the programs materials have, on the heap beyond that.
class Registers {
public:
    explicit Registers(const std::vector<float>& initial) {
        if (initial.size() > kOnStack) heap_.resize(initial.size());
        data_ = initial.size() > kOnStack ? heap_.data() : stack_;
        std::copy(initial.begin(), initial.end(), data_);
    }
    float* data() { return data_; }
    glm::vec3 vec(int r) const { return glm::vec3(data_[r], data_[r + 1], data_[r + 2]); }
    float at(int r) const { return data_[r]; }

private:
    static constexpr size_t kOnStack = 512;
    float stack_[kOnStack];
    std::vector<float> heap_;
    float* data_;
};

float finite_or(float v, float fallback) { return std::isfinite(v) ? v : fallback; }
glm::vec3 finite_or(const glm::vec3& v, const glm::vec3& fallback) {
    return glm::vec3(finite_or(v.x, fallback.x), finite_or(v.y, fallback.y), finite_or(v.z, fallback.z));
}

// The normal a program made, as Cycles gives it to the closures: tilted so that reflections of the view stay above
// the surface (ensure_valid_reflection).
glm::vec3 closure_normal(glm::vec3 n, const SurfacePoint& s, const glm::vec3& wo) {
    n = finite_or(n, glm::vec3(0.0f));
    const float len = glm::length(n);
    if (!(len > 0.0f)) return s.smooth_normal;
    return ensure_valid_reflection(s.geometric_normal, wo, n / len);
}

}  // namespace

ShaderGlobals shader_globals(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo) {
    ShaderGlobals g;
    const Instance& instance = scene.instances()[s.instance];
    const MeshData& mesh = scene.meshes()[instance.mesh];
    g.P = glm::vec3(glm::dvec3(s.position) + scene.origin());
    g.N = s.smooth_normal;
    g.Ng = s.geometric_normal;
    g.I = wo;
    g.backfacing = !s.entering;
    g.mesh = &mesh;
    g.instance = &instance;
    g.triangle = s.triangle;
    g.bary = s.bary;
    g.object_to_world_linear = glm::mat3(instance.to_world);
    g.world_to_object_linear = glm::inverse(g.object_to_world_linear);
    const size_t t = s.triangle;
    const glm::vec3& p0 = mesh.positions[mesh.indices[3 * t]];
    const glm::vec3& p1 = mesh.positions[mesh.indices[3 * t + 1]];
    const glm::vec3& p2 = mesh.positions[mesh.indices[3 * t + 2]];
    g.object_position = (1.0f - s.bary.x - s.bary.y) * p0 + s.bary.x * p1 + s.bary.y * p2 + mesh.centre;

    // The ray's footprint: a camera pixel at this distance (Cycles' ray differentials, for the first hit).
    const ShaderCamera& cam = scene.shader_camera();
    float dP = cam.orthographic ? cam.pixel_spread : cam.pixel_spread * glm::length(g.P - cam.position);
    if (!(dP > 0.0f) || !std::isfinite(dP)) dP = 1e-3f * std::max(1.0f, glm::length(g.object_position));
    g.dP = dP;
    glm::vec3 a, b;
    cycles_orthonormals(g.Ng, a, b);
    g.dPdx = dP * a;
    g.dPdy = dP * b;
    // Barycentric changes along dPdx, dPdy: least squares in the triangle's plane (world space).
    const glm::vec3 e1 = g.object_to_world_linear * (p1 - p0), e2 = g.object_to_world_linear * (p2 - p0);
    const float g11 = glm::dot(e1, e1), g12 = glm::dot(e1, e2), g22 = glm::dot(e2, e2);
    const float det = g11 * g22 - g12 * g12;
    if (det > 0.0f && std::isfinite(det)) {
        const auto solve = [&](const glm::vec3& d) {
            const float r1 = glm::dot(d, e1), r2 = glm::dot(d, e2);
            return glm::vec2(g22 * r1 - g12 * r2, g11 * r2 - g12 * r1) / det;
        };
        g.dbary_dx = solve(g.dPdx);
        g.dbary_dy = solve(g.dPdy);
    }

    g.camera_ray = s.ray_kind == ShaderRay::camera;
    g.shadow_ray = s.ray_kind == ShaderRay::shadow;
    g.singular_ray = s.ray_kind == ShaderRay::reflected;
    g.diffuse_ray = s.ray_kind == ShaderRay::photon;
    g.ray_length = s.distance;
    g.ray_depth = s.ray_kind == ShaderRay::camera ? 0.0f : 1.0f;
    return g;
}

namespace {

const bool kTimePrograms = std::getenv("PHOTONSPLAT_PROGRAM_TIMING") != nullptr;
std::atomic<uint64_t> g_program_runs{0}, g_program_nanoseconds{0};

void run_and_apply(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo, ProgrammedMaterial& out);

}  // namespace

ProgramTiming program_timing(bool reset) {
    ProgramTiming t;
    t.runs = reset ? g_program_runs.exchange(0) : g_program_runs.load();
    t.seconds = 1e-9 * double(reset ? g_program_nanoseconds.exchange(0) : g_program_nanoseconds.load());
    return t;
}

// The last run on this thread: a hit is usually shaded right after surface_at ran its program for the normal
// (Bump), or its emission was read just before, with the same point and direction; the second call copies.
struct LastRun {
    const Material* material = nullptr;
    uint64_t revision = 0;  // Scene::revision(): unique over every scene and every change that moves a value
    uint32_t instance = 0, triangle = 0;
    glm::vec2 bary{0.0f};
    glm::vec3 wo{0.0f};
    ShaderRay kind = ShaderRay::camera;
    ProgrammedMaterial result;

    bool same(const Scene& sc, const SurfacePoint& s, const glm::vec3& w) const {
        return revision == sc.revision() && material == s.material && instance == s.instance && triangle == s.triangle &&
               bary == s.bary && wo == w && kind == s.ray_kind;
    }
};

void run_material_program(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo, ProgrammedMaterial& out) {
    thread_local LastRun last;
    if (last.same(scene, s, wo)) {
        out = last.result;
        return;
    }
    if (!kTimePrograms) {
        run_and_apply(scene, s, wo, out);
    } else {
        const auto start = std::chrono::steady_clock::now();
        run_and_apply(scene, s, wo, out);
        const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start);
        g_program_runs.fetch_add(1, std::memory_order_relaxed);
        g_program_nanoseconds.fetch_add(static_cast<uint64_t>(ns.count()), std::memory_order_relaxed);
    }
    last.material = s.material;
    last.revision = scene.revision();
    last.instance = s.instance;
    last.triangle = s.triangle;
    last.bary = s.bary;
    last.wo = wo;
    last.kind = s.ray_kind;
    last.result = out;
}

namespace {

void run_and_apply(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo, ProgrammedMaterial& out) {
    const Material& m = *s.material;
    out.closure_count = static_cast<int>(std::min<size_t>(m.closures.size(), kMaxClosures));
    for (int i = 0; i < out.closure_count; ++i) out.closures[i] = m.closures[static_cast<size_t>(i)];
    out.emission = m.emission;
    out.has_normal = false;
    if (!m.programmed) return;
    const ShaderProgram& p = m.program;
    Registers r(p.registers);
    run_program(p, scene, shader_globals(scene, s, wo), r.data());
    for (const ProgramOutput& o : p.outputs) {
        Closure* c = o.index >= 0 && o.index < out.closure_count ? &out.closures[o.index] : nullptr;
        switch (o.target) {
            case ProgramTarget::closure_color:
                if (c) c->color = glm::max(finite_or(r.vec(o.register_), glm::vec3(0.0f)), glm::vec3(0.0f));
                break;
            case ProgramTarget::closure_specular_color:
                if (c) c->specular_color = glm::clamp(finite_or(r.vec(o.register_), glm::vec3(0.0f)), 0.0f, 1.0f);
                break;
            case ProgramTarget::closure_roughness:
                if (c) c->roughness = std::clamp(finite_or(r.at(o.register_), 0.0f), 0.0f, 1.0f);
                break;
            case ProgramTarget::closure_alpha_x:
                if (c) c->alpha_x = std::clamp(finite_or(r.at(o.register_), 0.0f), 0.0f, 1.0f);
                break;
            case ProgramTarget::closure_alpha_y:
                if (c) c->alpha_y = std::clamp(finite_or(r.at(o.register_), 0.0f), 0.0f, 1.0f);
                break;
            case ProgramTarget::closure_ior:
                if (c) c->ior = std::max(finite_or(r.at(o.register_), 1.45f), 1e-3f);
                break;
            case ProgramTarget::emission:  // signed, as Cycles' (negative emission darkens what it is added to)
                out.emission = finite_or(r.vec(o.register_), glm::vec3(0.0f));
                break;
            case ProgramTarget::normal:
                out.has_normal = true;
                out.normal = closure_normal(r.vec(o.register_), s, wo);
                break;
        }
    }
}

}  // namespace

glm::vec3 emission_at(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo) {
    const Material& m = *s.material;
    if (!m.program_emission) return m.emission;
    ProgrammedMaterial pm;
    run_material_program(scene, s, wo, pm);
    return pm.emission;
}

glm::vec3 program_normal(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo) {
    ProgrammedMaterial pm;
    run_material_program(scene, s, wo, pm);
    return pm.has_normal ? pm.normal : s.smooth_normal;
}

SurfacePoint surface_on_triangle(const Scene& scene, uint32_t instance, uint32_t triangle, float u, float v) {
    const WorldTriangle w = scene.world_triangle(instance, triangle);
    const glm::vec3 p = (1.0f - u - v) * w.v0 + u * w.v1 + v * w.v2;
    glm::vec3 n = glm::cross(w.v1 - w.v0, w.v2 - w.v0);
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
    // A ray arriving against the winding normal: the front face.
    Hit hit;
    hit.t = 0.0f;
    hit.instance = instance;
    hit.triangle = triangle;
    hit.u = u;
    hit.v = v;
    return surface_at(scene, Ray{p + n, -n}, hit);
}

}  // namespace ps
