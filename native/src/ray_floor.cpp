#include "photonsplat/ray_floor.h"

#include <algorithm>
#include <atomic>
#include <chrono>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/camera.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/scene.h"

namespace ps {

RayFloor measure_ray_floor(const Scene& scene, const Camera& world_camera) {
    const Camera camera = world_camera.relative_to(scene.origin());
    const RayTracer& tracer = scene.ray_tracer();  // built before the clock starts
    const int width = camera.width(), height = camera.height();
    constexpr int kTileWidth = 4, kTileHeight = RayTracer::kPacketRays / kTileWidth;
    std::atomic<uint64_t> hits{0};
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<int>(0, (height + kTileHeight - 1) / kTileHeight),
                      [&](const tbb::blocked_range<int>& rows) {
        uint64_t found_here = 0;
        for (int row = rows.begin(); row < rows.end(); ++row) {
            for (int x0 = 0; x0 < width; x0 += kTileWidth) {
                Ray rays[RayTracer::kPacketRays];
                float t_min[RayTracer::kPacketRays], t_max[RayTracer::kPacketRays];
                int count = 0;
                for (int dy = 0; dy < kTileHeight; ++dy) {
                    for (int dx = 0; dx < kTileWidth; ++dx) {
                        const int x = x0 + dx, y = row * kTileHeight + dy;
                        if (x >= width || y >= height) continue;
                        rays[count] = camera.generate_ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
                        t_min[count] = 0.0f;
                        t_max[count] = camera.far_distance(rays[count]);
                        ++count;
                    }
                }
                Hit hit[RayTracer::kPacketRays];
                bool found[RayTracer::kPacketRays];
                tracer.intersect(rays, t_min, t_max, count, kCameraRays, hit, found);
                for (int k = 0; k < count; ++k) found_here += found[k] ? 1 : 0;
            }
        }
        hits += found_here;
    });
    RayFloor floor;
    floor.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    floor.rays = static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
    floor.hits = hits.load();
    return floor;
}

}  // namespace ps
