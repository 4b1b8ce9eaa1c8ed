// What a render reports about itself: wall time per stage, counters of the work done, bytes per structure.
// Plain name→value maps so the bindings can turn them into a Python dict without knowing each entry.
#pragma once
#include <chrono>
#include <cstdint>
#include <map>
#include <string>

namespace ps {

struct Stats {
    std::map<std::string, double> seconds;     // stage name → wall time in seconds
    std::map<std::string, double> counters;    // e.g. "photon_sample_tests", "contributing_pairs"
    std::map<std::string, double> bytes;       // structure name → bytes held
    std::map<std::string, double> values;      // derived settings actually used, e.g. "radius"
    std::map<std::string, double> predicted_bytes;  // structure name → bytes predicted before allocating it

    void merge(const Stats& other);
};

// Adds the wall time between construction and destruction to stats.seconds[stage].
class StageTimer {
public:
    StageTimer(Stats& stats, std::string stage)
        : stats_(stats), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
    ~StageTimer() {
        std::chrono::duration<double> d = std::chrono::steady_clock::now() - start_;
        stats_.seconds[stage_] += d.count();
    }
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

private:
    Stats& stats_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace ps
