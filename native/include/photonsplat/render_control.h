// The thin channel between a running render and whoever started it: the render publishes its stage and
// progress, the caller may ask it to stop. Everything is atomic or locked, so any thread may read or write.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "photonsplat/errors.h"

namespace ps {

class RenderControl {
public:
    // Asked by the caller (another thread); honoured at the next check().
    void request_cancel() { cancel_.store(true, std::memory_order_relaxed); }
    bool cancel_requested() const { return cancel_.load(std::memory_order_relaxed); }

    // Called by the render between and inside stages: throws Cancelled once a cancel was requested.
    void check() const {
        if (cancel_requested()) throw Cancelled();
    }

    // Called by the render as each stage starts: its short name ("view samples", "photons", ...) and the
    // part [start, end] of the whole render it covers.
    void begin_stage(const std::string& stage, double start, double end) {
        std::lock_guard<std::mutex> lock(mutex_);
        stage_ = prefix_ + stage;
        start_ = span_start_ + (span_end_ - span_start_) * start;
        end_ = span_start_ + (span_end_ - span_start_) * end;
        within_.store(0.0, std::memory_order_relaxed);
    }
    // Called by a render made of parts (progressive passes): the stages that follow cover [start, end] of the
    // whole instead of [0, 1], and their names get `prefix` ("pass 3/8: ").
    void set_span(double start, double end, const std::string& prefix) {
        std::lock_guard<std::mutex> lock(mutex_);
        span_start_ = start;
        span_end_ = end;
        prefix_ = prefix;
    }
    // Called from inside a stage (any thread) as work completes: `done` of `total` units.
    void advance(uint64_t done, uint64_t total) const {
        if (total > 0) within_.store(static_cast<double>(done) / static_cast<double>(total), std::memory_order_relaxed);
    }
    // The current stage and the overall fraction in [0, 1].
    void progress(std::string& stage, double& fraction) const {
        std::lock_guard<std::mutex> lock(mutex_);
        stage = stage_;
        fraction = start_ + (end_ - start_) * std::min(1.0, within_.load(std::memory_order_relaxed));
    }

private:
    std::atomic<bool> cancel_{false};
    mutable std::mutex mutex_;
    std::string stage_ = "starting";
    double start_ = 0.0, end_ = 0.0;
    double span_start_ = 0.0, span_end_ = 1.0;
    std::string prefix_;
    mutable std::atomic<double> within_{0.0};
};

}  // namespace ps
