#include "photonsplat/direct_light.h"

#include <atomic>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/light_sources.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"

namespace ps {

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
            Rng rng(settings.seed, RngDomain::direct_light, s.pixel);
            glm::vec3 sum(0.0f);
            for (size_t l = 0; l < sources.size(); ++l) {
                const int n = sources.is_delta(l) ? 1 : settings.samples_per_light;
                glm::vec3 light_sum(0.0f);
                for (int k = 0; k < n; ++k) {
                    const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
                    const LightIncidence in = sources.sample_incidence(l, x, s.normal, u1, u2, u3);
                    // Light must arrive on the side the camera sees; the shading normal only weights it.
                    if (!(glm::dot(in.wi, s.normal) > 0.0f)) continue;
                    const float cos_shading = glm::dot(in.wi, s.shading_normal);
                    if (!(cos_shading > 0.0f) || in.value == glm::vec3(0.0f)) continue;
                    ++rays;
                    const Ray shadow{offset_ray_origin(x, s.normal), in.wi};
                    // Stop just short of the light's own point so the light's surroundings still shadow it.
                    if (tracer.occluded(shadow, 0.0f, in.distance * (1.0f - 1e-4f))) continue;
                    light_sum += in.value * cos_shading;
                }
                sum += light_sum / static_cast<float>(n);
            }
            out[i] = s.throughput * s.albedo * inv_pi * sum;
        }
        shadow_rays += rays;
        control.advance(samples_done += range.size(), samples.samples.size());
    });
    control.check();
    stats.counters["shadow_rays"] += static_cast<double>(shadow_rays.load());
    return out;
}

}  // namespace ps
