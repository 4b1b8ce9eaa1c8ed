// Small pieces shared by the native sources (not part of the public headers): a growing bounding box and a
// thread-safe meter of bytes held, with its peak.
#pragma once
#include <atomic>
#include <cstdint>
#include <limits>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

namespace ps {

struct Box {
    glm::vec3 lo{std::numeric_limits<float>::infinity()};
    glm::vec3 hi{-std::numeric_limits<float>::infinity()};
    // Argument order matters: glm::min(a, b) returns a when b is NaN, so NaN positions never poison a box
    // (they also never pass the per-sample distance test, so no box needs to contain them).
    void add(const glm::vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void add(const Box& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
};

// Bytes held by a splat's buffers and lists, and their peak (what stats report); updated from several threads.
class ByteMeter {
public:
    void add(int64_t delta) {
        const int64_t now = held_.fetch_add(delta, std::memory_order_relaxed) + delta;
        int64_t peak = peak_.load(std::memory_order_relaxed);
        while (now > peak && !peak_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
        }
    }
    int64_t peak() const { return peak_.load(std::memory_order_relaxed); }

private:
    std::atomic<int64_t> held_{0}, peak_{0};
};

}  // namespace ps
