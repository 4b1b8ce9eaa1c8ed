#include "photonsplat/kernel_coverage.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/shading.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"

namespace ps {

namespace {

// The share of a view sample's reflection that is diffuse-like (Lambert, Oren–Nayar, Principled diffuse, sheen,
// velvet), by Cycles' sampling weights: the part whose light changes as slowly over the kernel as Lambert's, for
// which dividing by the coverage is right.
float diffuse_share(const ViewSample& s, const std::vector<Lobe>& lobes) {
    if (!(s.flags & kGlossy)) return 1.0f;
    float diffuse = (s.albedo.x + s.albedo.y + s.albedo.z) / 3.0f, total = diffuse;
    for (uint32_t k = 0; k < s.lobe_count && s.lobe_begin + k < lobes.size(); ++k) {
        const Lobe& lobe = lobes[s.lobe_begin + k];
        float w = lobe_sampling_weight(lobe, s.shading_normal, s.wo);
        w = std::isfinite(w) ? std::max(w, 0.0f) : 0.0f;
        total += w;
        if (is_diffuse_reflection(lobe)) diffuse += w;
    }
    return total > 0.0f && std::isfinite(diffuse / total) ? std::clamp(diffuse / total, 0.0f, 1.0f) : 0.0f;
}

constexpr int kMaxSpecularCrossings = 4;  // mirrors and glass a probe passes through before it gives up
// A probe's surface this near the sample's normal, at the sample's height: the sample's own plane going on.
constexpr float kSamePlaneCosine = 0.9995f;

// What a probe finds of the surface photons land on: along the segment from `start` in direction `down` (length
// `length`), the first surface that stores photons (one with a closure that reflects other than a delta: diffuse,
// glossy, rough glass's reflection; or a translucent one, which stores caustic photons for the far sides of camera
// paths through it), if it faces within the splat's tolerance of `normal`. Surfaces that only pass light on (mirrors,
// sharp glass, rough refraction, transparency) are passed through: the photons they send on land behind them. A
// surface that both transmits and reflects stops the probe: photons land on it, and its own view samples are
// probed (seed 150 of the differential scenes: passing through a translucent and diffuse cylinder's wall found
// nothing, and its outside was estimated 2-2.6x too bright). Returns the
// cosine between that surface's normal and `normal` (0 when the probe finds no such surface) and the distance
// along the segment.
struct ProbeHit {
    float cosine = 0.0f;
    float t = 0.0f;
};

// The probe along `ray` (of `length`) from its first hit on: past specular surfaces to the surface it finds.
ProbeHit probe_from(const Scene& scene, const Ray& ray, Hit hit, float length, const glm::vec3& normal,
                    float cos_tolerance) {
    for (int crossing = 0;; ++crossing) {
        // Only the material and the geometric normal matter here, not the whole shading point (surface_at).
        const Instance& instance = scene.instances()[hit.instance];
        const MeshData& mesh = scene.meshes()[instance.mesh];
        const Material& material = scene.materials()[mesh.materials[hit.triangle]];
        if (material.reflects || material.translucent) {
            const glm::vec3& p0 = mesh.positions[mesh.indices[3 * size_t(hit.triangle)]];
            const glm::vec3& p1 = mesh.positions[mesh.indices[3 * size_t(hit.triangle) + 1]];
            const glm::vec3& p2 = mesh.positions[mesh.indices[3 * size_t(hit.triangle) + 2]];
            glm::vec3 ng = glm::normalize(instance.normal_to_world * glm::cross(p1 - p0, p2 - p0));
            if (glm::dot(ng, ray.direction) >= 0.0f) ng = -ng;  // the side the probe came from, as surface_at
            const float cosine = glm::dot(ng, normal);
            return cosine > cos_tolerance ? ProbeHit{cosine, hit.t} : ProbeHit{};
        }
        if (crossing == kMaxSpecularCrossings) return {};
        const float t_min = std::nextafter(hit.t, length) + 1e-6f * length;  // just past the specular surface
        if (!scene.ray_tracer().intersect(ray, t_min, length, hit, kPhotonReceivers)) return {};
    }
}

// Whether the surface a hit found stores photons (probe_from says which): the segments' test of what blocks.
bool receives_photons(const Scene& scene, const Hit& hit) {
    const Instance& instance = scene.instances()[hit.instance];
    const Material& material = scene.materials()[scene.meshes()[instance.mesh].materials[hit.triangle]];
    return material.reflects || material.translucent;
}

// Whether `ray` gets from t_min to t_max without meeting a surface photons land on (mirrors and glass are passed
// through, as probes pass them).
bool clear(const Scene& scene, const Ray& ray, float t_min, float t_max) {
    Hit hit;
    for (int crossing = 0; crossing <= kMaxSpecularCrossings; ++crossing) {
        if (!scene.ray_tracer().intersect(ray, t_min, t_max, hit, kPhotonReceivers)) return true;
        if (receives_photons(scene, hit)) return false;
        t_min = std::nextafter(hit.t, t_max) + 1e-6f * t_max;  // just past the specular surface
    }
    return false;
}

// Probe k lies in the k-th of kCoverageProbes equal-area rings of the tangent disc, at a random radius within it
// (a fixed radius would misjudge a surface that ends inside the ring), so it stands for 1/kCoverageProbes of the
// disc's area. One pattern (radii and angles in each sample's tangent frame) serves every sample of a call: the
// coverage then varies smoothly along a surface instead of from pixel to pixel, which on the caustic Cornell box
// raises the SSIM of a pass (0.859 -> 0.867 at 256²), and passes, which draw new patterns, average it.
struct ProbePattern {
    glm::vec2 offset[kCoverageProbes];  // in units of r, in the tangent frame
    float plane = 0.0f;                 // what a plane through the centre gives: the coverage's denominator
    bool uniform = true;

    ProbePattern(uint64_t seed, Kernel kernel) : uniform(kernel == Kernel::uniform) {
        Rng rng(seed, RngDomain::kernel_coverage, 0);
        const float rotation = 6.2831853f * rng.uniform();
        constexpr float kGoldenAngle = 2.39996323f;
        for (int k = 0; k < kCoverageProbes; ++k) {
            const float rho = std::sqrt((k + rng.uniform()) / kCoverageProbes);
            const float angle = rotation + k * kGoldenAngle;
            offset[k] = rho * glm::vec2(std::cos(angle), std::sin(angle));
            plane += uniform ? 1.0f : 2.0f * (1.0f - rho * rho);
        }
    }
};

// The coverage of one sample: the kernel-weighted area of photon-receiving surface inside the kernel's ball over
// π r², the area the estimate divides by. The surface a probe finds stands for its share of the disc over the
// cosine of its tilt (a tilted or curved surface holds more area above the same patch of disc: a sphere cut by a
// ball centred on it holds exactly π r²), weighted by the kernel at its distance from the centre. Divided by
// what a plane through the centre would give at the same probes, so that a plane's coverage is exactly 1.
float sample_coverage(const Scene& scene, const ViewSample& s, const glm::vec3& origin, const SplatParams& params,
                      const ProbePattern& pattern) {
    const float r = params.radius;
    const glm::vec3 x = s.position + origin;
    glm::vec3 tangent, bitangent;
    orthonormal_basis(s.normal, tangent, bitangent);
    // The probes are parallel and side by side: their first hits are traced as one packet.
    static_assert(kCoverageProbes <= RayTracer::kPacketRays, "one packet holds a sample's probes");
    Ray rays[kCoverageProbes];
    float t_min[kCoverageProbes], length[kCoverageProbes], rho2[kCoverageProbes];
    for (int k = 0; k < kCoverageProbes; ++k) {
        const glm::vec2 d = r * pattern.offset[k];
        rho2[k] = glm::dot(d, d);
        // The kernel is a ball: at distance ρ from its centre it reaches h above and below the plane.
        const float h = std::sqrt(std::max(r * r - rho2[k], 0.0f));
        const glm::vec3 q = x + d.x * tangent + d.y * bitangent;
        rays[k] = Ray{q + h * s.normal, -s.normal};
        t_min[k] = 0.0f;
        length[k] = 2.0f * h;
    }
    Hit first[kCoverageProbes];
    bool found[kCoverageProbes];
    scene.ray_tracer().intersect(rays, t_min, length, kCoverageProbes, kPhotonReceivers, first, found);
    // What each probe found, and the probes that found the sample's own plane going on: those count only if the
    // sample reaches the probe's column (its top, at least half the radius above the disc: a segment grazing the
    // disc's plane would meet it; above the tangent plane all the way, the segment never meets the sample's own
    // convex surface). A plane going on behind a wall standing on it, or below a floor laid across it, is in the
    // wall's or the floor's shadow, and none of the sample's light lands there. Other surfaces in the ball keep
    // counting whatever lies between: the splat gathers their photons too (overlapping letters of a text under a
    // wide kernel, each lit, would otherwise be brightened up to 1 / kMinCoverage). Counting them darkened the
    // pixel row along the foot of a lit wall to 0.882 of Cycles' (tests/blender/test_kernel_coverage_walls.py).
    ProbeHit hits[kCoverageProbes];
    Ray segments[kCoverageProbes];
    float segment_min[kCoverageProbes], segment_length[kCoverageProbes];
    int checked[kCoverageProbes], checks = 0;
    // Lifted by a thousandth of the radius (and past the surface's rounding), and blind for as long again (a sample
    // on the very edge where a wall meets a floor starts on the wall's plane): relative to the kernel, so that the
    // segments meet the same surfaces at every scale.
    const float skip = 1e-3f * r;
    const glm::vec3 from = offset_ray_origin(x + skip * s.normal, s.normal, s.rounding_scale);
    for (int k = 0; k < kCoverageProbes; ++k) {
        if (!found[k]) continue;
        hits[k] = probe_from(scene, rays[k], first[k], length[k], s.normal, params.cos_normal_tolerance);
        const float height = 0.5f * length[k] - hits[k].t;  // of the surface found, above the tangent plane
        if (hits[k].cosine > kSamePlaneCosine && std::fabs(height) < skip) {
            const glm::vec3 column = rays[k].origin + std::max(0.0f, 0.5f * r - 0.5f * length[k]) * s.normal;
            const glm::vec3 d = column - from;
            const float l = glm::length(d);
            if (!(l > skip) || !std::isfinite(l)) continue;
            segments[checks] = Ray{from, d / l};
            segment_min[checks] = skip;
            segment_length[checks] = l;
            checked[checks++] = k;
        }
    }
    // The segments leave one point: traced as one packet; one that meets a mirror or glass goes on past it alone.
    Hit blocker[kCoverageProbes];
    bool met[kCoverageProbes];
    if (checks > 0)
        scene.ray_tracer().intersect(segments, segment_min, segment_length, checks, kPhotonReceivers, blocker, met);
    for (int c = 0; c < checks; ++c) {
        if (!met[c]) continue;
        const float past = std::nextafter(blocker[c].t, segment_length[c]) + 1e-6f * segment_length[c];
        if (receives_photons(scene, blocker[c]) || !clear(scene, segments[c], past, segment_length[c]))
            hits[checked[c]].cosine = 0.0f;  // not reached: the probe finds nothing of the sample's light
    }
    float area = 0.0f;
    for (int k = 0; k < kCoverageProbes; ++k) {
        if (!found[k] || hits[k].cosine == 0.0f) continue;
        const float h = 0.5f * length[k];
        const float height = h - hits[k].t;
        const float weight =
            pattern.uniform ? 1.0f : std::max(2.0f * (1.0f - (rho2[k] + height * height) / (r * r)), 0.0f);
        area += weight / hits[k].cosine;
    }
    return pattern.plane > 0.0f ? std::max(area / pattern.plane, kMinCoverage) : 1.0f;
}

// Whether sample b lies on the same flat surface as a, within a quarter of the kernel's radius: near enough for
// a's coverage to stand for b's.
bool alike(const ViewSample& a, const ViewSample& b, float radius) {
    const glm::vec3 d = b.position - a.position;
    return glm::dot(a.normal, b.normal) > 0.9995f && std::fabs(glm::dot(a.normal, d)) < 1e-3f * radius &&
           glm::dot(d, d) < 0.0625f * radius * radius;
}

// Every kGridStep-th column and row is probed. At 3 the probe rays are 0.57 of a grid of 2 on the atrium at
// 1080p (0.15 of probing every pixel; a pixel whose grid neighbours are not alike is probed too), and the 64-pass
// images keep an SSIM of 0.9987 (Cornell box) and 0.998 (atrium) against the checkerboard's of db0ead1
// (tools/progressive_ssim.py, 480 x 270); 4 saved little more (more pixels fell back to probing).
constexpr int kGridStep = 3;

template <typename Body>
bool for_each_sample(size_t count, const RenderControl& control, const Body& body) {
    std::atomic<bool> cancelled{false};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1024), [&](const tbb::blocked_range<size_t>& range) {
        if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
            cancelled = true;
            return;
        }
        for (size_t i = range.begin(); i < range.end(); ++i) body(i);
    });
    return !cancelled;
}

}  // namespace

std::vector<float> kernel_coverage(const Scene& scene, const ViewSamples& samples, const SplatParams& params,
                                   uint64_t seed, const RenderControl& control, Stats& stats,
                                   const std::vector<uint8_t>* wanted) {
    const size_t count = samples.samples.size();
    std::vector<float> coverage(count, 1.0f);
    if (count == 0 || !(params.radius > 0.0f)) return coverage;
    const ProbePattern pattern(seed, params.kernel);
    // Glossy parts keep their estimate: where the kernel is wider than a curved glossy surface (glossy_row's
    // spheres) dividing by the coverage brightened their lit tops and lowered the SSIM of every iteration
    // (docs/results/README.md, "Boundary correction"). A sample's diffuse-like part takes the correction: a room of
    // Oren–Nayar or Principled walls, whose parts are all diffuse-like, lost light at its corners (differential
    // seed 184's walls alone: 0.9965 of Cycles, 0.9999 as Lambert walls). The coverage of a sample with diffuse
    // share d is 1 − (1 − c) d, set once the grid's raw coverages have been blended.
    std::vector<float> share(count, 0.0f);
    bool done = for_each_sample(count, control, [&](size_t i) {
        if (!wanted || (*wanted)[i]) share[i] = diffuse_share(samples.samples[i], samples.lobes);
    });
    const auto probed = [&](size_t i) { return share[i] > 0.0f; };
    // The coverage changes over the kernel's width, many pixels wide: only the pixels of a grid (every
    // kGridStep-th column and row) are probed, and the others take the bilinear blend of the four grid pixels
    // around them, among those on the same flat surface (alike); where none is, they are probed too.
    constexpr int step = kGridStep;
    const int width = samples.width, height = samples.height;
    std::vector<uint32_t> first_sample(static_cast<size_t>(width) * height, UINT32_MAX);
    stats.bytes["kernel_coverage"] = static_cast<double>(coverage.capacity() * sizeof(float) +
                                                         first_sample.capacity() * sizeof(uint32_t));
    for (size_t i = count; i-- > 0;) first_sample[samples.samples[i].pixel] = static_cast<uint32_t>(i);
    // Probed directly: a pixel's further samples (its branches at glass) and the grid's pixels.
    const auto on_grid = [&](size_t i) {
        const ViewSample& s = samples.samples[i];
        return first_sample[s.pixel] != i || ((s.pixel % width) % step == 0 && (s.pixel / width) % step == 0);
    };
    std::atomic<uint64_t> probes{0};
    done = done && for_each_sample(count, control, [&](size_t i) {
        if (!probed(i) || !on_grid(i)) return;
        coverage[i] = sample_coverage(scene, samples.samples[i], samples.origin, params, pattern);
        probes.fetch_add(kCoverageProbes, std::memory_order_relaxed);
    });
    done = done && for_each_sample(count, control, [&](size_t i) {
        if (!probed(i) || on_grid(i)) return;
        const ViewSample& s = samples.samples[i];
        const int x = static_cast<int>(s.pixel % width), y = static_cast<int>(s.pixel / width);
        const int x0 = x - x % step, y0 = y - y % step;
        const float fx = float(x % step) / float(step), fy = float(y % step) / float(step);
        float sum = 0.0f, weights = 0.0f;
        for (int corner = 0; corner < 4; ++corner) {
            const int gx = x0 + (corner & 1) * step, gy = y0 + (corner >> 1) * step;
            const float w = ((corner & 1) ? fx : 1.0f - fx) * ((corner >> 1) ? fy : 1.0f - fy);
            if (!(w > 0.0f) || gx >= width || gy >= height) continue;
            const uint32_t j = first_sample[static_cast<size_t>(gy) * width + gx];
            if (j == UINT32_MAX || !probed(j) || !alike(s, samples.samples[j], params.radius)) continue;
            sum += w * coverage[j];
            weights += w;
        }
        if (weights > 0.0f) {
            coverage[i] = sum / weights;
        } else {
            coverage[i] = sample_coverage(scene, s, samples.origin, params, pattern);
            probes.fetch_add(kCoverageProbes, std::memory_order_relaxed);
        }
    });
    done = done && for_each_sample(count, control, [&](size_t i) {
        if (share[i] < 1.0f) coverage[i] = 1.0f - (1.0f - coverage[i]) * share[i];
    });
    if (!done) control.check();
    stats.counters["coverage_probes"] += static_cast<double>(probes.load());
    return coverage;
}

}  // namespace ps
