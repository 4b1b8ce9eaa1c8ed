#include "photonsplat/caustic_aim.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "photonsplat/light_sources.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"

#include "building_blocks.h"

namespace ps {

namespace {

constexpr float kPi = 3.14159265358979323846f;

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The sphere around a set of points: centred on their box, reaching the farthest.
SpecularTarget sphere_around(const std::vector<glm::vec3>& points) {
    Box box;
    for (const glm::vec3& p : points) box.add(p);
    const glm::vec3 center = 0.5f * (box.lo + box.hi);
    float r2 = 0.0f;
    for (const glm::vec3& p : points) r2 = std::max(r2, glm::dot(p - center, p - center));
    return {center, std::sqrt(r2)};
}

}  // namespace

std::vector<SpecularTarget> specular_targets(const Scene& scene) {
    // Per mesh, the vertices of its specular triangles (object space), found once.
    std::vector<std::vector<glm::vec3>> specular_vertices(scene.meshes().size());
    std::vector<bool> looked(scene.meshes().size(), false);
    std::vector<uint32_t> instances;
    for (uint32_t i = 0; i < scene.instances().size(); ++i) {
        const Instance& inst = scene.instances()[i];
        if (!(inst.visibility & kIndirectRays)) continue;  // photons pass through it
        if (!looked[inst.mesh]) {
            looked[inst.mesh] = true;
            const MeshData& mesh = scene.meshes()[inst.mesh];
            for (size_t t = 0; t < mesh.triangle_count(); ++t)
                if (scene.materials()[mesh.materials[t]].has_delta)
                    for (int c = 0; c < 3; ++c) specular_vertices[inst.mesh].push_back(mesh.positions[mesh.indices[3 * t + c]]);
        }
        if (!specular_vertices[inst.mesh].empty()) instances.push_back(i);
    }
    auto world_points = [&](uint32_t i, bool corners_only) {
        const Instance& inst = scene.instances()[i];
        std::vector<glm::vec3> points;
        const std::vector<glm::vec3>& local = specular_vertices[inst.mesh];
        if (corners_only) {
            Box box;
            for (const glm::vec3& p : local) box.add(p);
            for (int c = 0; c < 8; ++c)
                points.push_back(glm::vec3((c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                                           (c & 4) ? box.hi.z : box.lo.z));
        } else {
            points = local;
        }
        for (glm::vec3& p : points) p = glm::vec3(inst.to_world * glm::vec4(p, 1.0f));
        return points;
    };
    std::vector<SpecularTarget> targets;
    if (instances.size() <= kMaxSpecularTargets) {
        for (uint32_t i : instances) {
            const SpecularTarget t = sphere_around(world_points(i, false));
            if (finite(t.center) && std::isfinite(t.radius)) targets.push_back(t);
        }
    } else {
        // Many specular instances (a field of instanced glass): one sphere around their boxes.
        std::vector<glm::vec3> corners;
        for (uint32_t i : instances) {
            const std::vector<glm::vec3> c = world_points(i, true);
            corners.insert(corners.end(), c.begin(), c.end());
        }
        const SpecularTarget t = sphere_around(corners);
        if (finite(t.center) && std::isfinite(t.radius)) targets.push_back(t);
    }
    return targets;
}

TargetCones::TargetCones(const std::vector<SpecularTarget>& targets, const Light& light, const glm::vec3& from,
                         float extra_radius) {
    // Directions the light emits into: all, a spot's cone (half angle spot_size/2), an area light's front side.
    bool limited = false;
    glm::vec3 emit_axis(0.0f);
    float emit_half_angle = kPi;
    if (light.kind == LightKind::spot) {
        limited = true;
        emit_axis = glm::normalize(light.direction);
        emit_half_angle = 0.5f * light.spot_size;
    } else if (light.kind == LightKind::area) {
        limited = true;
        emit_axis = light.area_normal();
        emit_half_angle = 0.5f * kPi;
    }
    for (size_t i = 0; i < targets.size() && i < kMaxSpecularTargets; ++i) {
        const SpecularTarget& t = targets[i];
        const glm::vec3 to = t.center - from;
        const float d = glm::length(to);
        const float r = t.radius + extra_radius;
        Cone cone;
        if (!(d > r)) {
            // Inside the grown sphere: every direction may reach it.
            cone.axis = glm::vec3(0.0f, 0.0f, 1.0f);
            cone.cos_max = -1.0f;
            cone.solid_angle = 4.0f * kPi;
        } else {
            cone.axis = to / d;
            const float sin2 = (r / d) * (r / d);
            cone.cos_max = std::sqrt(std::max(0.0f, 1.0f - sin2));
            cone.solid_angle = 2.0f * kPi * sin2 / (1.0f + cone.cos_max);  // 2π(1 − cos), without cancellation
            if (limited) {
                const float half = std::asin(std::min(1.0f, r / d));
                const float apart = std::acos(std::clamp(glm::dot(cone.axis, emit_axis), -1.0f, 1.0f));
                if (apart >= emit_half_angle + half) continue;  // the light sends nothing that way
            }
        }
        if (!(cone.solid_angle > 0.0f) || !finite(cone.axis)) continue;
        cones_[count_++] = cone;
        total_ += cone.solid_angle;
    }
}

glm::vec3 TargetCones::sample(float u_cone, float u1, float u2) const {
    float running = 0.0f;
    size_t k = 0;
    const float goal = u_cone * total_;
    for (; k + 1 < count_; ++k) {
        running += cones_[k].solid_angle;
        if (goal < running) break;
    }
    const Cone& c = cones_[k];
    if (c.cos_max <= -1.0f) return sample_uniform_sphere(u1, u2);
    return sample_uniform_cone(c.axis, c.cos_max, u1, u2);
}

float TargetCones::pdf(const glm::vec3& direction) const {
    int holding = 0;
    for (size_t k = 0; k < count_; ++k) holding += glm::dot(direction, cones_[k].axis) >= cones_[k].cos_max ? 1 : 0;
    return holding > 0 ? static_cast<float>(holding) / total_ : 0.0f;
}

CausticAim::CausticAim(const Scene& scene, const LightSources& sources, const std::vector<float>& source_probability,
                       float aimed_fraction)
    : sources_(sources), source_probability_(source_probability), aimed_fraction_(aimed_fraction) {
    aimed_probability_.assign(sources.size(), 0.0f);
    if (!(aimed_fraction > 0.0f) || source_probability.size() != sources.size()) return;
    targets_ = specular_targets(scene);
    if (targets_.empty()) return;
    // Aimed photons go to the lights that can aim, in proportion to their power like ordinary ones.
    double total = 0.0;
    std::vector<double> weight(sources.size(), 0.0);
    for (size_t i = 0; i < sources.size(); ++i) {
        const Light* light = sources.light(i);
        if (light && light_can_aim(*light) && source_probability[i] > 0.0f) weight[i] = source_probability[i];
        total += weight[i];
    }
    if (!(total > 0.0)) return;
    double running = 0.0;
    for (size_t i = 0; i < sources.size(); ++i) {
        running += weight[i];
        aimed_probability_[i] = static_cast<float>(weight[i] / total);
        aim_cdf_.push_back(static_cast<float>(running / total));
    }
    aim_cdf_.back() = 1.0f;
}

size_t CausticAim::pick_source(float u) const {
    const size_t k = static_cast<size_t>(std::upper_bound(aim_cdf_.begin(), aim_cdf_.end(), u) - aim_cdf_.begin());
    size_t which = std::min(k, aim_cdf_.size() - 1);
    while (aimed_probability_[which] <= 0.0f && which > 0) --which;  // a float tie at a zero-width step
    return which;
}

glm::vec3 CausticAim::anchor_of(const Light& light, const EmissionSample& emitted) const {
    return light.kind == LightKind::area ? emitted.origin : light.position;
}

float CausticAim::balance(size_t source, float aim_pdf, float own_pdf) const {
    if (!(aim_pdf > 0.0f)) return 1.0f;
    const float ratio = aimed_fraction_ * aimed_probability_[source] * aim_pdf /
                        (source_probability_[source] * own_pdf);
    return std::isfinite(ratio) ? 1.0f / (1.0f + ratio) : 0.0f;
}

EmissionSample CausticAim::sample(size_t source, Rng& rng) const {
    const Light& light = *sources_.light(source);
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const float u_cone = rng.uniform(), v1 = rng.uniform(), v2 = rng.uniform();
    const float w1 = rng.uniform(), w2 = rng.uniform();
    const glm::vec3 anchor = emission_anchor(light, u1, u2);
    const float extra = light.kind == LightKind::area ? 0.0f : light.radius;
    const TargetCones cones(targets_, light, anchor, extra);
    EmissionSample out;
    out.origin = anchor;
    out.direction = glm::vec3(0.0f, 0.0f, 1.0f);
    out.power = glm::vec3(0.0f);
    if (cones.empty()) return out;
    const glm::vec3 direction = cones.sample(u_cone, v1, v2);
    const float own = emission_direction_pdf(light, anchor, direction);
    if (!(own > 0.0f)) return out;
    out = emission_along(light, anchor, direction, w1, w2);
    out.power *= balance(source, cones.pdf(direction), own);
    return out;
}

float CausticAim::ordinary_caustic_weight(size_t source, const EmissionSample& emitted) const {
    if (!(aimed_probability_[source] > 0.0f)) return 1.0f;
    const Light& light = *sources_.light(source);
    const glm::vec3 anchor = anchor_of(light, emitted);
    const float extra = light.kind == LightKind::area ? 0.0f : light.radius;
    const TargetCones cones(targets_, light, anchor, extra);
    const float own = emission_direction_pdf(light, anchor, emitted.direction);
    return balance(source, cones.pdf(emitted.direction), own);
}

}  // namespace ps
