// What a render reports about itself: wall time per stage, counters of the work done, bytes per structure.
// Plain name→value maps so the bindings can turn them into a Python dict without knowing each entry.
#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <string>

namespace ps {

// Rays traced, counted per thread at no cost to the tracing (each thread writes only its own counter) and summed
// on demand: StageTimer reports each stage's rays, for its rays per second beside Embree's floor
// (docs/benchmarks.md). Process-wide: two renders running at once (viewport and F12) count each other's too.
struct ThreadRays {
    std::atomic<uint64_t> count{0};
    ThreadRays();
    ~ThreadRays();
    void add(uint64_t n) { count.store(count.load(std::memory_order_relaxed) + n, std::memory_order_relaxed); }
};
inline thread_local ThreadRays thread_rays;
inline void count_rays(uint64_t n) { thread_rays.add(n); }
uint64_t rays_traced();

struct Stats {
    std::map<std::string, double> seconds;     // stage name → wall time in seconds
    std::map<std::string, double> counters;    // e.g. "photon_sample_tests", "contributing_pairs"
    std::map<std::string, double> bytes;       // structure name → bytes held
    std::map<std::string, double> values;      // derived settings actually used, e.g. "radius"
    std::map<std::string, double> predicted_bytes;  // structure name → bytes predicted before allocating it

    void merge(const Stats& other);
};

// Adds the wall time between construction and destruction to stats.seconds[stage], and the rays traced meanwhile
// (when any) to stats.counters["rays." + stage].
class StageTimer {
public:
    StageTimer(Stats& stats, std::string stage)
        : stats_(stats), stage_(std::move(stage)), rays_(rays_traced()), start_(std::chrono::steady_clock::now()) {}
    ~StageTimer() {
        std::chrono::duration<double> d = std::chrono::steady_clock::now() - start_;
        stats_.seconds[stage_] += d.count();
        const uint64_t rays = rays_traced() - rays_;
        if (rays > 0) stats_.counters["rays." + stage_] += static_cast<double>(rays);
    }
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

private:
    Stats& stats_;
    std::string stage_;
    uint64_t rays_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace ps
