#include "photonsplat/view_samples.h"

#include <atomic>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"

namespace ps {

size_t ViewSamples::bytes() const {
    return samples.capacity() * sizeof(ViewSample) + emission.capacity() * sizeof(glm::vec3) +
           alpha.capacity() * sizeof(float) + first_normal.capacity() * sizeof(glm::vec3) +
           first_depth.capacity() * sizeof(float);
}

namespace {

// Below this cosine between the shading normal and the viewer, a glossy sample shades with its geometric normal.
constexpr float kMinGlossyCosine = 1e-3f;

// Follows one camera ray through mirrors and glass. Returns true and fills `sample` at the first non-specular
// (diffuse or glossy) hit; adds emission and background seen along the way to `emitted`. The first hit's
// normal and depth go to `first_normal` / `first_depth` (left untouched when the ray escapes).
bool trace_camera_path(const Scene& scene, const Camera& camera, Ray ray, Rng& rng, int max_specular_depth,
                       ViewSample& sample, glm::vec3& emitted, float& alpha, glm::vec3& first_normal,
                       float& first_depth) {
    const RayTracer& tracer = scene.ray_tracer();
    glm::vec3 throughput(1.0f);
    for (int depth = 0;; ++depth) {
        Hit hit;
        // The first segment sees what is visible to the camera, up to its far clip; later ones what is visible
        // to indirect rays.
        const bool first = depth == 0;
        if (!tracer.intersect(ray, 0.0f, first ? camera.far_distance(ray) : std::numeric_limits<float>::infinity(),
                              hit, first ? kCameraRays : kIndirectRays)) {
            emitted += throughput * scene.background();
            return false;
        }
        const SurfacePoint s = surface_at(scene, ray, hit);
        if (first) {
            if (s.material->holdout) return false;  // cut out: alpha stays 0, nothing is added
            alpha = 1.0f;
            sample.depth = camera.view_depth(s.position);
            first_depth = sample.depth;
            first_normal = s.shading_normal;  // already on the side the camera ray came from
        }
        emitted += throughput * s.material->emission;
        if (!s.material->is_specular()) {
            sample.position = s.position;  // made camera-relative by the caller
            sample.normal = s.geometric_normal;
            sample.shading_normal = s.shading_normal;
            sample.rounding_scale = s.rounding_scale;
            sample.wo = -ray.direction;
            sample.throughput = throughput;
            sample.flags = depth > 0 ? kViaSpecular : 0u;
            if (s.material->is_glossy()) {
                // A pure GGX lobe (no diffuse part): F0 = colour, α = roughness².
                sample.albedo = glm::vec3(0.0f);
                sample.specular = s.color;
                sample.roughness = s.material->glossy_alpha();
                sample.flags |= kGlossy;
                // Where interpolation tilts the shading normal away from the viewer (silhouettes of smooth
                // meshes), the lobe would see ωo below its surface and reflect nothing: black rims. Use the
                // geometric normal there, which always faces the viewer.
                if (!(glm::dot(sample.shading_normal, sample.wo) > kMinGlossyCosine))
                    sample.shading_normal = sample.normal;
            } else {
                sample.albedo = s.color;
                sample.specular = glm::vec3(0.0f);
                sample.roughness = 0.0f;
            }
            return true;
        }
        if (depth >= max_specular_depth) return false;
        const SpecularStep step = scatter_specular(*s.material, s, ray.direction, rng.uniform());
        throughput *= step.weight;
        if (throughput.x <= 0.0f && throughput.y <= 0.0f && throughput.z <= 0.0f) return false;
        const glm::vec3 side = step.transmitted ? -s.geometric_normal : s.geometric_normal;
        ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), step.direction};
    }
}

}  // namespace

ViewSamples generate_view_samples(const Scene& scene, const Camera& world_camera, const ViewSampleSettings& settings,
                                  const RenderControl& control, Stats& stats) {
    StageTimer timer(stats, "view_samples");
    // Render space (scene.h); render_pass has done it already, but this stage is also called on its own.
    const Camera camera = world_camera.relative_to(scene.origin());
    const int width = camera.width(), height = camera.height();
    const size_t pixels = static_cast<size_t>(width) * height;
    ViewSamples out;
    out.width = width;
    out.height = height;
    out.origin = camera.position();
    out.emission.assign(pixels, glm::vec3(0.0f));
    out.alpha.assign(pixels, 0.0f);
    out.first_normal.assign(pixels, glm::vec3(0.0f));
    out.first_depth.assign(pixels, 0.0f);

    std::vector<ViewSample> per_pixel(pixels);
    std::vector<uint8_t> has_sample(pixels, 0);
    scene.ray_tracer();  // build the BVH once, before the threads need it
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> rows_done{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 8), [&](const tbb::blocked_range<int>& rows) {
        if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
            cancelled = true;
            return;
        }
        for (int y = rows.begin(); y < rows.end(); ++y) {
            for (int x = 0; x < width; ++x) {
                const size_t pixel = static_cast<size_t>(y) * width + x;
                Rng rng(settings.seed, RngDomain::camera, pixel);
                float jx = 0.5f, jy = 0.5f;
                if (settings.jitter) {
                    Rng jitter(settings.seed, RngDomain::pixel_jitter, pixel);
                    jx = jitter.uniform();
                    jy = jitter.uniform();
                }
                const Ray ray = camera.generate_ray(static_cast<float>(x) + jx, static_cast<float>(y) + jy);
                ViewSample& sample = per_pixel[pixel];
                sample.pixel = static_cast<uint32_t>(pixel);
                if (trace_camera_path(scene, camera, ray, rng, settings.max_specular_depth, sample,
                                      out.emission[pixel], out.alpha[pixel], out.first_normal[pixel],
                                      out.first_depth[pixel])) {
                    sample.position -= out.origin;
                    has_sample[pixel] = 1;
                }
            }
        }
        control.advance(rows_done += rows.size(), static_cast<uint64_t>(height));
    });
    control.check();

    size_t count = 0;
    for (uint8_t h : has_sample) count += h;
    out.samples.reserve(count);
    for (size_t p = 0; p < pixels; ++p)
        if (has_sample[p]) out.samples.push_back(per_pixel[p]);
    stats.counters["view_samples"] += static_cast<double>(count);
    stats.bytes["view_samples"] = static_cast<double>(out.bytes());
    return out;
}

}  // namespace ps
