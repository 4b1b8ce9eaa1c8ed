#include "photonsplat/direct_light.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/brdf.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"

namespace ps {

namespace {

// A light's samples at a view sample are stratified over the (u1, u2) square its sampling maps to a point or a
// direction: a √n × √n jittered grid when n is a square (the default 4: 2 × 2), else n strips along u1. Each
// sample stays uniform within its cell and the cells are equal, so the estimate keeps its expectation; what
// changes is that the n samples cover the light (or the sky's hemisphere) evenly instead of clumping, which
// lowers the noise of partly hidden lights: soft shadows, the sky seen through an opening.
struct StrataGrid {
    int columns = 1, rows = 1;
    void place(int k, float& u1, float& u2) const {
        if (columns * rows == 1) return;
        constexpr float kBelowOne = 0x1.fffffep-1f;  // (cell + u) / cells may round up to 1 otherwise
        u1 = std::min((static_cast<float>(k % columns) + u1) / static_cast<float>(columns), kBelowOne);
        u2 = std::min((static_cast<float>(k / columns) + u2) / static_cast<float>(rows), kBelowOne);
    }
};

StrataGrid strata_grid(int n) {
    const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n))));
    if (side * side == n) return {side, side};
    return {n, 1};
}

}  // namespace

std::vector<glm::vec3> compute_direct_light(const Scene& scene, const ViewSamples& samples,
                                            const DirectLightSettings& settings, const RenderControl& control,
                                            Stats& stats) {
    StageTimer timer(stats, "direct_light");
    std::vector<glm::vec3> out(samples.samples.size(), glm::vec3(0.0f));
    const LightSources sources(scene);
    if (sources.size() == 0 || samples.samples.empty()) return out;
    const RayTracer& tracer = scene.ray_tracer();
    const float inv_pi = 1.0f / 3.14159265358979323846f;
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> shadow_rays{0};
    std::atomic<uint64_t> samples_done{0};

    tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.samples.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
        if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
            cancelled = true;
            return;
        }
        uint64_t rays = 0;
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const ViewSample& s = samples.samples[i];
            const glm::vec3 x = s.position + samples.origin;
            // A pixel's second sample (the reflected branch at glass) draws its own numbers.
            Rng rng(settings.seed, RngDomain::direct_light,
                    uint64_t(s.pixel) + ((s.flags & kReflectedBranch) ? (uint64_t(1) << 32) : 0));
            const bool glossy = (s.flags & kGlossy) != 0;
            const glm::vec3 diffuse = s.albedo * inv_pi;
            // Σ over lights of incident radiance × cos, weighted by the BRDF where it depends on the direction
            // (glossy), or by nothing where it does not (a diffuse sample's ρ/π is applied once, at the end).
            glm::vec3 sum(0.0f);
            for (size_t l = 0; l < sources.size(); ++l) {
                const int n = sources.is_delta(l) ? 1 : settings.samples_per_light;
                const StrataGrid grid = strata_grid(n);
                glm::vec3 light_sum(0.0f);
                for (int k = 0; k < n; ++k) {
                    float u1 = rng.uniform(), u2 = rng.uniform();
                    const float u3 = rng.uniform();
                    grid.place(k, u1, u2);
                    if (glossy && sources.is_world(l)) {
                        // A glossy lobe under the sky: the world's cosine-weighted directions would almost never
                        // fall into a sharp lobe, so the lobe samples its own directions (weight f·cos/pdf), and
                        // light sampling is kept for the diffuse part only (zero for a pure glossy surface).
                        const GgxSample g = sample_ggx_reflection(s.specular, s.roughness, s.shading_normal, s.wo,
                                                                  u1, u2);
                        if (g.pdf > 0.0f && glm::dot(g.direction, s.normal) > 0.0f) {
                            ++rays;
                            const Ray ray{offset_ray_origin(x, s.normal, s.rounding_scale), g.direction};
                            if (!tracer.occluded(ray, 0.0f, std::numeric_limits<float>::infinity(), kShadowRays))
                                light_sum += g.weight * scene.background();
                        }
                        if (diffuse == glm::vec3(0.0f)) continue;
                    }
                    const LightIncidence in = sources.sample_incidence(l, x, s.normal, u1, u2, u3);
                    // Light must arrive on the side the camera sees; the shading normal only weights it.
                    if (!(glm::dot(in.wi, s.normal) > 0.0f)) continue;
                    const float cos_shading = glm::dot(in.wi, s.shading_normal);
                    if (!(cos_shading > 0.0f) || in.value == glm::vec3(0.0f)) continue;
                    ++rays;
                    const Ray shadow{offset_ray_origin(x, s.normal, s.rounding_scale), in.wi};
                    // Stop just short of the light's own point so the light's surroundings still shadow it.
                    if (tracer.occluded(shadow, 0.0f, in.distance * (1.0f - 1e-4f), kShadowRays)) continue;
                    if (!glossy)
                        light_sum += in.value * cos_shading;
                    else if (sources.is_world(l))
                        light_sum += in.value * cos_shading * diffuse;  // the glossy lobe was sampled above
                    else
                        light_sum += in.value * cos_shading * glm::vec3(sample_brdf(s, in.wi));
                }
                sum += light_sum / static_cast<float>(n);
            }
            out[i] = s.throughput * (glossy ? sum : diffuse * sum);
        }
        shadow_rays += rays;
        control.advance(samples_done += range.size(), samples.samples.size());
    });
    control.check();
    stats.counters["shadow_rays"] += static_cast<double>(shadow_rays.load());
    return out;
}

}  // namespace ps
