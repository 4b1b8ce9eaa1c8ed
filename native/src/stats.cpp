#include "photonsplat/stats.h"

#include <algorithm>
#include <mutex>
#include <vector>

namespace ps {

namespace {

// The live threads' counters and what finished threads counted. Never destroyed: worker threads may end after
// static destruction has begun.
struct RayCounters {
    std::mutex mutex;
    std::vector<ThreadRays*> live;
    uint64_t retired = 0;
};

RayCounters& ray_counters() {
    static RayCounters* counters = new RayCounters;
    return *counters;
}

}  // namespace

ThreadRays::ThreadRays() {
    RayCounters& c = ray_counters();
    std::lock_guard<std::mutex> lock(c.mutex);
    c.live.push_back(this);
}

ThreadRays::~ThreadRays() {
    RayCounters& c = ray_counters();
    std::lock_guard<std::mutex> lock(c.mutex);
    c.retired += count.load(std::memory_order_relaxed);
    c.live.erase(std::remove(c.live.begin(), c.live.end(), this), c.live.end());
}

uint64_t rays_traced() {
    RayCounters& c = ray_counters();
    std::lock_guard<std::mutex> lock(c.mutex);
    uint64_t total = c.retired;
    for (const ThreadRays* t : c.live) total += t->count.load(std::memory_order_relaxed);
    return total;
}

void Stats::merge(const Stats& other) {
    for (const auto& [k, v] : other.seconds) seconds[k] += v;
    for (const auto& [k, v] : other.counters) counters[k] += v;
    for (const auto& [k, v] : other.bytes) bytes[k] = v;
    for (const auto& [k, v] : other.values) values[k] = v;
    for (const auto& [k, v] : other.predicted_bytes) predicted_bytes[k] = v;
}

}  // namespace ps
