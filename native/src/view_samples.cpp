#include "photonsplat/view_samples.h"

#include <atomic>
#include <limits>
#include <optional>

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

// Where a camera path stands between two vertices: the ray leaving the last one, the product of specular weights
// so far and the number of specular bounces behind it.
struct CameraPath {
    Ray ray;
    glm::vec3 throughput;
    int depth;
};

// What the first surface a pixel's camera ray hits tells its pixel (as Cycles' passes).
struct FirstHit {
    float alpha = 0.0f;
    glm::vec3 normal{0.0f};
    float depth = 0.0f;
};

// Follows a camera path through mirrors and glass. Returns true and fills `sample` at the first non-specular
// (diffuse or glossy) hit; adds emission and background seen along the way to `emitted`. The first hit (depth 0)
// fills `first` (left untouched when the ray escapes). At its first glass surface, if `branch` is not null and
// the glass both reflects and refracts there, the path follows the refracted ray and leaves the reflected one,
// with its Fresnel weight, in *branch: the pixel then averages both instead of one chosen at random, which
// removes the speckle of glass (a reflection of the bright room in some pixels, the view through the glass in
// their neighbours) that would otherwise take many passes to average out.
bool trace_camera_path(const Scene& scene, const Camera& camera, CameraPath path, Rng& rng, int max_specular_depth,
                       ViewSample& sample, glm::vec3& emitted, FirstHit& first, std::optional<CameraPath>* branch) {
    const RayTracer& tracer = scene.ray_tracer();
    for (;; ++path.depth) {
        const Ray& ray = path.ray;
        Hit hit;
        // The first segment sees what is visible to the camera, up to its far clip; later ones what is visible
        // to indirect rays.
        const bool from_camera = path.depth == 0;
        if (!tracer.intersect(ray, 0.0f,
                              from_camera ? camera.far_distance(ray) : std::numeric_limits<float>::infinity(), hit,
                              from_camera ? kCameraRays : kIndirectRays)) {
            emitted += path.throughput * scene.background();
            return false;
        }
        const SurfacePoint s = surface_at(scene, ray, hit);
        if (from_camera) {
            if (s.material->holdout) return false;  // cut out: alpha stays 0, nothing is added
            first.alpha = 1.0f;
            first.depth = camera.view_depth(s.position);
            first.normal = s.shading_normal;  // already on the side the camera ray came from
        }
        emitted += path.throughput * s.material->emission;
        if (!s.material->is_specular()) {
            sample.position = s.position;  // made camera-relative by the caller
            sample.normal = s.geometric_normal;
            sample.shading_normal = s.shading_normal;
            sample.rounding_scale = s.rounding_scale;
            sample.wo = -ray.direction;
            sample.throughput = path.throughput;
            sample.flags = path.depth > 0 ? kViaSpecular : 0u;
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
        if (path.depth >= max_specular_depth) return false;
        SpecularStep step;
        if (branch != nullptr && s.material->kind == MaterialKind::glass) {
            const SpecularSplit split = split_specular(*s.material, s, ray.direction);
            if (split.both) {
                const glm::vec3 reflected = path.throughput * split.reflected.weight;
                if (reflected.x > 0.0f || reflected.y > 0.0f || reflected.z > 0.0f)
                    *branch = CameraPath{Ray{offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale),
                                             split.reflected.direction},
                                         reflected, path.depth + 1};
                step = split.transmitted;
            } else {
                step = split.reflected;
            }
            branch = nullptr;  // one split per pixel at most
        } else {
            step = scatter_specular(*s.material, s, ray.direction, rng.uniform());
        }
        path.throughput *= step.weight;
        if (path.throughput.x <= 0.0f && path.throughput.y <= 0.0f && path.throughput.z <= 0.0f) return false;
        const glm::vec3 side = step.transmitted ? -s.geometric_normal : s.geometric_normal;
        path.ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), step.direction};
    }
}

}  // namespace

ViewSamples generate_view_samples(const Scene& scene, const Camera& world_camera, const ViewSampleSettings& settings,
                                  const RenderControl& control, Stats& stats) {
    StageTimer timer(stats, "view_samples");
    // Render space (scene.h); render_iteration has done it already, but this stage is also called on its own.
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

    // Each band of rows collects its samples (up to two a pixel) in pixel order; the bands are joined in order,
    // so the result does not depend on which thread traced which band.
    constexpr int kBandRows = 8;
    const int bands = (height + kBandRows - 1) / kBandRows;
    std::vector<std::vector<ViewSample>> band_samples(static_cast<size_t>(bands));
    scene.ray_tracer();  // build the BVH once, before the threads need it
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> rows_done{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, bands), [&](const tbb::blocked_range<int>& range) {
        for (int band = range.begin(); band < range.end(); ++band) {
            if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
                cancelled = true;
                return;
            }
            // Collected here (a band's worth of memory per thread), then copied to a vector of exactly their size.
            std::vector<ViewSample> found;
            const int y_end = std::min(height, (band + 1) * kBandRows);
            found.reserve(static_cast<size_t>(y_end - band * kBandRows) * static_cast<size_t>(width));
            for (int y = band * kBandRows; y < y_end; ++y) {
                for (int x = 0; x < width; ++x) {
                    const size_t pixel = static_cast<size_t>(y) * width + x;
                    Rng rng(settings.seed, RngDomain::camera, pixel);
                    float jx = 0.5f, jy = 0.5f;
                    if (settings.jitter) {
                        Rng jitter(settings.seed, RngDomain::pixel_jitter, pixel);
                        jx = jitter.uniform();
                        jy = jitter.uniform();
                    }
                    const CameraPath start{
                        camera.generate_ray(static_cast<float>(x) + jx, static_cast<float>(y) + jy), glm::vec3(1.0f), 0};
                    ViewSample sample;
                    sample.pixel = static_cast<uint32_t>(pixel);
                    FirstHit first;
                    std::optional<CameraPath> reflected;
                    if (trace_camera_path(scene, camera, start, rng, settings.max_specular_depth, sample,
                                          out.emission[pixel], first, settings.split_at_glass ? &reflected : nullptr)) {
                        sample.depth = first.depth;
                        sample.position -= out.origin;
                        found.push_back(sample);
                    }
                    if (reflected && trace_camera_path(scene, camera, *reflected, rng, settings.max_specular_depth,
                                                       sample, out.emission[pixel], first, nullptr)) {
                        sample.depth = first.depth;
                        sample.position -= out.origin;
                        sample.flags |= kReflectedBranch;
                        found.push_back(sample);
                    }
                    out.alpha[pixel] = first.alpha;
                    out.first_normal[pixel] = first.normal;
                    out.first_depth[pixel] = first.depth;
                }
            }
            band_samples[static_cast<size_t>(band)].assign(found.begin(), found.end());
            control.advance(rows_done += static_cast<uint64_t>(y_end - band * kBandRows),
                            static_cast<uint64_t>(height));
        }
    });
    control.check();

    size_t count = 0;
    for (const std::vector<ViewSample>& found : band_samples) count += found.size();
    out.samples.reserve(count);
    for (std::vector<ViewSample>& found : band_samples) {
        out.samples.insert(out.samples.end(), found.begin(), found.end());
        std::vector<ViewSample>().swap(found);
    }
    stats.counters["view_samples"] += static_cast<double>(count);
    stats.bytes["view_samples"] = static_cast<double>(out.bytes());
    return out;
}

}  // namespace ps
