// The thin channel between a running render and whoever started it: the render publishes its stage and
// progress, the caller may ask it to stop. Everything is atomic or locked, so any thread may read or write.
#pragma once
#include <atomic>
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

    // stage: a short name ("view samples", "photons", ...); fraction: overall progress in [0, 1].
    void set_stage(const std::string& stage, double fraction) {
        std::lock_guard<std::mutex> lock(mutex_);
        stage_ = stage;
        fraction_ = fraction;
    }
    void progress(std::string& stage, double& fraction) const {
        std::lock_guard<std::mutex> lock(mutex_);
        stage = stage_;
        fraction = fraction_;
    }

private:
    std::atomic<bool> cancel_{false};
    mutable std::mutex mutex_;
    std::string stage_ = "starting";
    double fraction_ = 0.0;
};

}  // namespace ps
