#include "photonsplat/kernel_radius.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {

constexpr int kLossProbes = 8;   // probes of each disc
constexpr float kCoveredCosine = 0.5f;  // the splat kernel's default normal tolerance (cos 60°)
// The relative variance of a disc's photon estimate at default_radius, against which automatic_radius weighs the
// boundary bias. Calibrated on two measured trade-offs (docs/results/README.md, "Automatic radius"): on the
// caustic Cornell box default_radius was the best first radius of a progressive render, on the atrium about
// half of it. (1/128: as if a disc held 128 photons; it also absorbs that the boundary loss of the geometry is
// larger than the image's, whose direct light has no such bias.)
constexpr double kDiscVariance = 1.0 / 128.0;

// A point the camera sees first, where photons would be splatted.
struct SeenPoint {
    glm::vec3 position, normal, tangent, bitangent;
    float rotation;  // of the probe pattern, so that neighbouring points probe different directions
};

std::vector<SeenPoint> seen_points(const Scene& scene, const Camera& camera) {
    const int w = camera.width(), h = camera.height();
    const int longer = std::max(w, h);
    const int columns = std::max(1, std::min(w, kBoundaryLossGrid * w / longer));
    const int rows = std::max(1, std::min(h, kBoundaryLossGrid * h / longer));
    std::vector<SeenPoint> points;
    const RayTracer& tracer = scene.ray_tracer();
    for (int j = 0; j < rows; ++j) {
        for (int i = 0; i < columns; ++i) {
            const Ray ray = camera.generate_ray((i + 0.5f) * w / columns, (j + 0.5f) * h / rows);
            Hit hit;
            if (!tracer.intersect(ray, 0.0f, camera.far_distance(ray), hit, kCameraRays)) continue;
            const SurfacePoint s = surface_at(scene, ray, hit);
            if (s.material->holdout || s.material->is_specular()) continue;
            SeenPoint p;
            p.position = s.position;
            p.normal = s.geometric_normal;
            orthonormal_basis(p.normal, p.tangent, p.bitangent);
            Rng rng(0, RngDomain::kernel_probe, static_cast<uint64_t>(j) * columns + i);
            p.rotation = 6.2831853f * rng.uniform();
            points.push_back(p);
        }
    }
    return points;
}

// The fraction of kLossProbes probes of the disc around `p` that find no surface like p's within the kernel.
float uncovered_fraction(const Scene& scene, const SeenPoint& p, float radius) {
    const RayTracer& tracer = scene.ray_tracer();
    constexpr float kGoldenAngle = 2.39996323f;
    int uncovered = 0;
    for (int k = 0; k < kLossProbes; ++k) {
        const float rho = radius * std::sqrt((k + 0.5f) / kLossProbes);  // equal-area rings
        const float angle = p.rotation + k * kGoldenAngle;
        const glm::vec3 q = p.position + rho * (std::cos(angle) * p.tangent + std::sin(angle) * p.bitangent);
        // The kernel is a sphere: at distance rho from its centre it reaches `height` above and below the plane.
        const float height = std::sqrt(std::max(radius * radius - rho * rho, 0.0f));
        const Ray ray{q + height * p.normal, -p.normal};
        Hit hit;
        bool covered = false;
        if (tracer.intersect(ray, 0.0f, 2.0f * height, hit, kIndirectRays)) {
            const SurfacePoint s = surface_at(scene, ray, hit);
            covered = !s.material->is_specular() && glm::dot(s.geometric_normal, p.normal) > kCoveredCosine;
        }
        uncovered += covered ? 0 : 1;
    }
    return static_cast<float>(uncovered) / kLossProbes;
}

double mean_loss(const Scene& scene, const std::vector<SeenPoint>& points, float radius) {
    if (points.empty()) return 0.0;
    std::vector<float> loss(points.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 64), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) loss[i] = uncovered_fraction(scene, points[i], radius);
    });
    double sum = 0.0;  // in point order: the same figure whatever the threads
    for (float l : loss) sum += l;
    return sum / points.size();
}

}  // namespace

float default_radius(const Scene& scene, uint64_t photons) {
    // A kernel disc then holds roughly the same number of photons whatever their count.
    const float diagonal = glm::length(scene.bounds_max() - scene.bounds_min());
    const double n = static_cast<double>(std::max<uint64_t>(photons, 1));
    return static_cast<float>(0.015 * diagonal * std::sqrt(200000.0 / n));
}

float boundary_loss(const Scene& scene, const Camera& camera, float radius) {
    const Camera render_camera = camera.relative_to(scene.origin());
    return static_cast<float>(mean_loss(scene, seen_points(scene, render_camera), radius));
}

float automatic_radius(const Scene& scene, const Camera& camera, uint64_t photons) {
    const float largest = default_radius(scene, photons);
    const std::vector<SeenPoint> points = seen_points(scene, camera.relative_to(scene.origin()));
    // Candidates halve the disc's area at each step, down to a quarter of the radius. Each is scored by a
    // model of its relative squared error: the boundary bias squared plus the variance of a disc's photon
    // estimate, which grows as 1/s² when the radius is s × default_radius (s² as many photons per disc).
    float best_radius = largest;
    double best_error = std::numeric_limits<double>::infinity();
    for (int step = 0; step <= 4; ++step) {
        const double scale = std::pow(0.5, 0.5 * step);
        const float radius = static_cast<float>(largest * scale);
        const double bias = mean_loss(scene, points, radius);
        const double error = bias * bias + kDiscVariance / (scale * scale);
        if (error < best_error) best_error = error, best_radius = radius;
    }
    return best_radius;
}

}  // namespace ps
