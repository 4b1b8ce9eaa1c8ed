// Small pieces shared by the native sources (not part of the public headers): a growing bounding box, Morton
// keys over a box, and a thread-safe meter of bytes held, with its peak.
#pragma once
#include <atomic>
#include <cstdint>
#include <limits>

#include <cmath>

#include <glm/common.hpp>
#include <glm/vec3.hpp>
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

// Morton codes over a box, 10 bits an axis (30-bit keys): sorting points by key walks them in spatial order, so
// that neighbours meet the same nodes and cells while those are in cache.
class MortonGrid {
public:
    explicit MortonGrid(const Box& box)
        : lo_(box.lo), scale_(glm::dvec3(1023.0) / glm::max(glm::dvec3(box.hi) - glm::dvec3(box.lo), glm::dvec3(1e-30))) {}
    uint32_t key(const glm::vec3& p) const {  // 0 for a point with a non-finite coordinate
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return 0;
        const glm::dvec3 q = glm::clamp((glm::dvec3(p) - glm::dvec3(lo_)) * scale_, 0.0, 1023.0);
        return spread(uint32_t(q.x)) | spread(uint32_t(q.y)) << 1 | spread(uint32_t(q.z)) << 2;
    }

private:
    static uint32_t spread(uint32_t v) {  // bit i of a 10-bit value to bit 3i
        v &= 1023u;
        v = (v | v << 16) & 0x030000FFu;
        v = (v | v << 8) & 0x0300F00Fu;
        v = (v | v << 4) & 0x030C30C3u;
        v = (v | v << 2) & 0x09249249u;
        return v;
    }
    glm::vec3 lo_;
    glm::dvec3 scale_;
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
