// Splatting through the view-sample cluster hierarchy, in three steps:
//   1. traverse: each photon walks the hierarchy, skipping every node its sphere cannot reach, and records a
//      (leaf, photon) pair per leaf it may touch;
//   2. lists: a stable counting sort turns the pairs into one photon list per leaf, photon indices ascending;
//   3. shade: each leaf shades its own samples from its list (so no two threads write one output), adding to a
//      double sum per sample.
// Each sample thus sees the photons that can reach it in ascending index order, exactly as in `brute`, and
// the output is the same bit for bit unless the compiler orders the arithmetic differently.
//
// Bounded memory. The pairs grow as photons × leaves touched: with a radius as large as the scene that is
// photons × all leaves (~1.9e10 pairs at 1080p with 200k photons). So photons are splatted in batches of
// consecutive indices, each sorted and shaded before the next is added, and the per-sample sums carry over from
// batch to batch. Batches come in ascending photon order and each list is ascending, so every sample still adds
// its photons in ascending index order into one glm::dvec3: the output does not depend on where batches end.
//
// The pairs held at once stay under SplatParams::max_pairs_in_memory (the cap). The photons flow through an
// ordered pipeline:
//   - a serial stage cuts the photons into consecutive ranges, sized from the pairs per photon seen so far so
//     that a range is expected to hold half of `range_pairs` (1024 photons at most, a few at the start);
//   - ranges are traversed in parallel, `ranges_in_flight` at once; a range stops before a photon once it holds
//     `range_pairs` pairs (never before its first photon, so one photon that alone exceeds the cap still works);
//   - a serial stage takes ranges in photon order, traverses what is left of a range that stopped (in pieces,
//     in order), and adds the pieces to the batch, sorting and shading the batch first when a piece would take
//     it past `batch_pairs`. It also counts the pairs per leaf as they come, overlapping the lists' first pass
//     with the traversal.
// In flight are at most ranges_in_flight × range_pairs pairs (= cap − batch_pairs), plus the pairs of one
// photon per range; ranges_in_flight is lowered where the leaves are many for the cap so that this excess
// stays under cap / 2. When everything fits, which a typical radius does, there is one batch, shaded once
// traversal is over, as without batches; the pipeline then costs about what a parallel loop over chunks would.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/validation.h"

namespace ps {
namespace {

// Photon ranges: at most this many photons (enough to make a range's overhead negligible), and this many while
// nothing is known yet about the pairs per photon (small, so that a huge radius does not start with ranges that
// must stop early and be finished serially).
constexpr size_t kMaxPhotonsPerRange = 1024;
constexpr size_t kFirstPhotonsPerRange = 16;
// The share of the cap for ranges in flight: 1/16. The rest is for the batch.
constexpr uint64_t kInFlightShareDivisor = 16;

// Squared distance from p to the box, written with the same float operations as the per-sample test's
// dot(x − p, x − p). For x in the box, each gap component is a correctly rounded difference that is never
// larger in magnitude than the rounded x − p on that axis (rounding is monotone), and squaring and summing
// are monotone too: so this is never larger than the distance the per-sample test computes for any sample
// in the box. Rejecting when it is >= r² could therefore never lose a sample; the reject threshold adds a
// 1e-5 relative margin on top in case the compiler contracts one of the two expressions into FMAs.
float distance_sq_to_box(const glm::vec3& p, const ClusterNode& node) {
    const glm::vec3 gap = glm::max(glm::max(node.box_min - p, p - node.box_max), glm::vec3(0.0f));
    return glm::dot(gap, gap);
}

// How the cap is shared out (see the top of the file).
struct PairBudget {
    size_t ranges_in_flight = 1;
    size_t range_pairs = 1;  // a range stops before a photon (not its first) once it holds this many pairs
    size_t batch_pairs = 0;  // a batch is shaded before a piece would take it past this (unless it is empty)
};

PairBudget pair_budget(uint64_t max_pairs, size_t leaf_count, size_t threads) {
    const uint64_t cap = std::max<uint64_t>(max_pairs, 1);
    PairBudget b;
    // Each range in flight may go past range_pairs by one photon's pairs, at most one per leaf.
    const uint64_t ranges = cap / (2 * std::max<uint64_t>(leaf_count, 1));
    b.ranges_in_flight = size_t(std::clamp<uint64_t>(ranges, 1, 2 * std::max<uint64_t>(threads, 1)));
    const uint64_t in_flight = std::max<uint64_t>(b.ranges_in_flight, cap / kInFlightShareDivisor);
    b.range_pairs = size_t(in_flight / b.ranges_in_flight);
    b.batch_pairs = size_t(cap - std::min(cap, in_flight));
    return b;
}

// The pairs of consecutive photons [begin, end), photon by photon (the photon of a pair is implied).
struct Segment {
    uint32_t begin = 0;
    uint32_t end = 0;              // one past the last photon traversed so far
    uint32_t range_end = 0;        // one past the last photon of the range this segment is (the start of)
    size_t expected_pairs = 0;     // a capacity hint
    std::vector<uint32_t> leaves;  // the leaf node of every pair, photons ascending
    std::vector<uint32_t> ends;    // ends[j − begin]: one past photon j's last pair in `leaves`
    uint64_t node_tests = 0;
    size_t bytes() const { return (leaves.capacity() + ends.capacity()) * sizeof(uint32_t); }
};

// Bytes held in pair buffers and lists, and the peak of that; updated from several threads.
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

class ClusterSplat {
public:
    ClusterSplat(const ClusterHierarchy& hierarchy, const ViewSamples& samples, const PhotonMap& photons,
                 const SplatParams& params, const RenderControl& control, Stats& stats)
        : hierarchy_(hierarchy),
          views_(samples.samples),
          photons_(photons.photons),
          params_(params),
          control_(control),
          stats_(stats),
          positions_(relative_photon_positions(photons, samples.origin)),
          radiance_(views_.size(), glm::vec3(0.0f)) {
        const float r = params.radius;
        reject_distance_sq_ = (r * r) * (1.0f + 1e-5f);
        budget_ = pair_budget(params.max_pairs_in_memory, hierarchy.leaves.size(),
                              size_t(tbb::this_task_arena::max_concurrency()));
    }

    std::vector<glm::vec3> run() {
        // offsets_[n + 2] counts leaf n's pairs of the batch so far (see shade_batch).
        offsets_.assign(hierarchy_.nodes.size() + 2, 0);
        meter_.add(int64_t(offsets_.capacity() * sizeof(size_t)));
        const auto start = std::chrono::steady_clock::now();
        const auto cut = tbb::make_filter<void, Segment*>(
            tbb::filter_mode::serial_in_order, [this](tbb::flow_control& fc) { return next_range(fc); });
        const auto walk = tbb::make_filter<Segment*, Segment*>(tbb::filter_mode::parallel, [this](Segment* segment) {
            traverse(*segment);
            return segment;
        });
        const auto take = tbb::make_filter<Segment*, void>(tbb::filter_mode::serial_in_order, [this](Segment* segment) {
            take_range(*segment);
            release(segment);
        });
        tbb::parallel_pipeline(budget_.ranges_in_flight, cut & walk & take);
        const std::chrono::duration<double> pipeline = std::chrono::steady_clock::now() - start;
        // The pipeline's time, less the batches it shaded on the way: traversal (overlapped with counting).
        stats_.seconds["splat_traverse"] += pipeline.count() - seconds_in_batches_;
        shade_batch(true);

        stats_.counters["photon_node_tests"] += double(node_tests_);
        stats_.counters["photon_sample_tests"] += double(sample_tests_.load());
        stats_.counters["contributing_pairs"] += double(contributing_.load());
        stats_.counters["leaf_photon_pairs"] += double(total_pairs_);
        stats_.counters["splat_batches"] += double(batches_);
        stats_.bytes["leaf_photon_lists"] = double(meter_.peak());
        stats_.bytes["splat_sample_sums"] = double(sums_.capacity() * sizeof(glm::dvec3));
        return std::move(radiance_);
    }

private:
    // Input stage (serial): the next range of photons.
    Segment* next_range(tbb::flow_control& fc) {
        if (next_photon_ == positions_.size()) {
            fc.stop();
            return nullptr;
        }
        const double estimate = pairs_per_photon_.load(std::memory_order_relaxed);
        size_t count = kFirstPhotonsPerRange;
        if (estimate >= 0.0) {
            const double fit = double(budget_.range_pairs) / (2.0 * std::max(estimate, 1e-3));
            count = size_t(std::clamp(fit, 1.0, double(kMaxPhotonsPerRange)));
        }
        Segment* segment = acquire();
        segment->begin = segment->end = uint32_t(next_photon_);
        next_photon_ = std::min(positions_.size(), next_photon_ + count);
        segment->range_end = uint32_t(next_photon_);
        if (estimate >= 0.0)
            segment->expected_pairs = size_t(std::min(double(budget_.range_pairs), 1.25 * estimate * double(count)));
        return segment;
    }

    // Traverses photons from segment.end on, until the range ends or the segment holds range_pairs pairs.
    void traverse(Segment& segment) {
        const size_t before = segment.bytes();
        segment.leaves.reserve(segment.expected_pairs);
        segment.ends.reserve(segment.range_end - segment.end);
        std::vector<uint32_t> stack;
        stack.reserve(7 * size_t(hierarchy_.depth) + 1);  // depth-first: at most 7 siblings waiting per level
        for (uint32_t j = segment.end; j != segment.range_end; ++j) {
            if (j != segment.begin && segment.leaves.size() >= budget_.range_pairs) break;
            control_.check();
            const glm::vec3& p = positions_[j];
            if (is_finite(p)) {  // else it can pass no per-sample test, and would visit every node
                stack.push_back(hierarchy_.root);
                while (!stack.empty()) {
                    const uint32_t index = stack.back();
                    stack.pop_back();
                    const ClusterNode& node = hierarchy_.nodes[index];
                    ++segment.node_tests;
                    if (distance_sq_to_box(p, node) > reject_distance_sq_) continue;
                    if (node.child_count == 0) {
                        segment.leaves.push_back(index);
                    } else {
                        for (uint32_t c = node.child_count; c-- > 0;) stack.push_back(node.first_child + c);
                    }
                }
            }
            segment.ends.push_back(uint32_t(segment.leaves.size()));
            segment.end = j + 1;
        }
        meter_.add(int64_t(segment.bytes()) - int64_t(before));
    }

    // The pipeline's tokens are Segment pointers into segments_, which owns them: TBB does not destroy the tokens
    // of a pipeline that an exception (a cancel) stopped. At most ranges_in_flight are in use at once.
    Segment* acquire() {
        std::lock_guard<std::mutex> lock(segments_mutex_);
        if (free_segments_.empty()) {
            segments_.push_back(std::make_unique<Segment>());
            return segments_.back().get();
        }
        Segment* segment = free_segments_.back();
        free_segments_.pop_back();
        return segment;
    }

    void release(Segment* segment) {
        *segment = Segment();  // its buffers were moved to the batch; this resets the rest
        std::lock_guard<std::mutex> lock(segments_mutex_);
        free_segments_.push_back(segment);
    }

    // Output stage (serial, in photon order): adds a traversed range to the batch, finishing it here if it
    // stopped early, and updates the estimate of pairs per photon.
    void take_range(Segment& first) {
        const uint32_t range_begin = first.begin, range_end = first.range_end;
        size_t pairs = first.leaves.size();
        uint32_t done = first.end;
        add_to_batch(first);
        while (done != range_end) {
            Segment rest;
            rest.begin = rest.end = done;
            rest.range_end = range_end;
            traverse(rest);
            pairs += rest.leaves.size();
            done = rest.end;
            add_to_batch(rest);
        }
        // Follows a rise at once and a fall slowly: ranges sized for too few pairs stop early, and their rest
        // is traversed serially here.
        // Progress: photons traversed, then (in the last batch) leaves shaded.
        control_.advance(range_end, positions_.size() + hierarchy_.leaves.size());
        const double sample = double(pairs) / double(range_end - range_begin);
        const double previous = pairs_per_photon_.load(std::memory_order_relaxed);
        pairs_per_photon_.store(previous < 0.0 ? sample : std::max(sample, 0.75 * previous + 0.25 * sample),
                                std::memory_order_relaxed);
    }

    void add_to_batch(Segment& segment) {
        const size_t pairs = segment.leaves.size();
        if (batch_pairs_ > 0 && batch_pairs_ + pairs > budget_.batch_pairs) {
            const auto start = std::chrono::steady_clock::now();
            shade_batch(false);
            const std::chrono::duration<double> d = std::chrono::steady_clock::now() - start;
            seconds_in_batches_ += d.count();
        }
        for (const uint32_t leaf : segment.leaves) ++offsets_[leaf + 2];
        node_tests_ += segment.node_tests;
        batch_pairs_ += pairs;
        total_pairs_ += pairs;
        batch_.push_back(std::move(segment));  // moves the buffers out of the pipeline's token
    }

    // Sorts the batch's pairs into per-leaf lists and shades the leaves. With `last`, every sample is finished;
    // otherwise the leaves with photons add them to their samples' sums.
    void shade_batch(bool last) {
        {
            StageTimer timer(stats_, "splat_lists");
            // offsets_[n + 2] holds leaf n's count; the prefix sum makes offsets_[n + 1] the start of leaf n's
            // list, and filling advances it to the list's end, which is the start of leaf n + 1's: then
            // leaf n's photons are list_[offsets_[n], offsets_[n + 1]), with no cursor array.
            for (size_t n = 0; n + 2 < offsets_.size(); ++n) offsets_[n + 2] += offsets_[n + 1];
            const size_t before = list_.capacity() * sizeof(uint32_t);
            if (batch_pairs_ > list_.capacity()) {  // exactly: resize alone would double the capacity
                list_ = std::vector<uint32_t>();
                list_.reserve(last ? batch_pairs_ : std::max(batch_pairs_, budget_.batch_pairs));
            }
            list_.resize(batch_pairs_);
            meter_.add(int64_t(list_.capacity() * sizeof(uint32_t)) - int64_t(before));
            for (Segment& segment : batch_) {  // photon order: every list comes out ascending
                size_t k = 0;
                for (uint32_t j = segment.begin; j != segment.end; ++j)
                    for (const size_t end = segment.ends[j - segment.begin]; k != end; ++k)
                        list_[offsets_[segment.leaves[k] + 1]++] = j;
                meter_.add(-int64_t(segment.bytes()));
                segment = Segment();  // release as we go: the pairs and the lists are the two largest buffers
            }
            batch_.clear();
        }
        control_.check();
        if (!last && sums_.empty()) sums_.assign(views_.size(), glm::dvec3(0.0));
        {
            StageTimer timer(stats_, "splat_shade");
            const std::vector<uint32_t>& leaves = hierarchy_.leaves;
            tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size(), 16),
                              [&](const tbb::blocked_range<size_t>& range) { shade_leaves(range, last); });
        }
        std::fill(offsets_.begin(), offsets_.end(), size_t(0));
        batch_pairs_ = 0;
        ++batches_;
    }

    void shade_leaves(const tbb::blocked_range<size_t>& range, bool last) {
        const bool carried = !sums_.empty();
        uint64_t tests = 0, contributing = 0;
        for (size_t l = range.begin(); l != range.end(); ++l) {
            const uint32_t leaf = hierarchy_.leaves[l];
            const uint32_t* list = list_.data() + offsets_[leaf];
            const size_t list_size = offsets_[leaf + 1] - offsets_[leaf];
            if (list_size == 0 && !last) continue;
            control_.check();
            if (last) {
                const uint64_t shaded = leaves_shaded_.fetch_add(1, std::memory_order_relaxed) + 1;
                if ((shaded & 255) == 0)
                    control_.advance(positions_.size() + shaded, positions_.size() + hierarchy_.leaves.size());
            }
            const ClusterNode& node = hierarchy_.nodes[leaf];
            for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
                const uint32_t i = hierarchy_.sample_order[k];
                const ViewSample& s = views_[i];
                glm::dvec3 reflected_flux = carried ? sums_[k] : glm::dvec3(0.0);
                for (size_t m = 0; m != list_size; ++m) {
                    const uint32_t j = list[m];
                    if (!photon_reaches_sample(s, positions_[j], photons_[j], params_)) continue;
                    reflected_flux += photon_reflected_flux(s, photons_[j]);
                    ++contributing;
                }
                if (last)
                    radiance_[i] = finish_sample(s, reflected_flux, params_);
                else
                    sums_[k] = reflected_flux;
            }
            tests += uint64_t(list_size) * (node.sample_end - node.sample_begin);
        }
        sample_tests_ += tests;
        contributing_ += contributing;
    }

    const ClusterHierarchy& hierarchy_;
    const std::vector<ViewSample>& views_;
    const std::vector<Photon>& photons_;
    const SplatParams& params_;
    const RenderControl& control_;
    Stats& stats_;
    const std::vector<glm::vec3> positions_;
    float reject_distance_sq_ = 0.0f;
    PairBudget budget_;

    size_t next_photon_ = 0;                      // input stage
    std::atomic<double> pairs_per_photon_{-1.0};  // output stage → input stage; < 0 until known
    std::atomic<uint64_t> leaves_shaded_{0};       // in the last batch, for progress
    std::mutex segments_mutex_;                   // input and output stages
    std::vector<std::unique_ptr<Segment>> segments_;
    std::vector<Segment*> free_segments_;

    std::vector<Segment> batch_;    // output stage: the pairs of the batch, photons ascending
    size_t batch_pairs_ = 0;
    std::vector<size_t> offsets_;   // pair counts per leaf while filling, then the lists' CSR offsets
    std::vector<uint32_t> list_;    // the batch's per-leaf photon lists
    std::vector<glm::dvec3> sums_;  // per position in sample_order: Σ f_r·Φ so far; empty while one batch
    std::vector<glm::vec3> radiance_;

    ByteMeter meter_;
    uint64_t node_tests_ = 0, total_pairs_ = 0, batches_ = 0;
    std::atomic<uint64_t> sample_tests_{0}, contributing_{0};
    double seconds_in_batches_ = 0.0;
};

}  // namespace

std::vector<glm::vec3> splat_cluster(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                     const PhotonMap& photons, const SplatParams& params,
                                     const RenderControl& control, Stats& stats) {
    validate(params, photons);
    const std::vector<ViewSample>& views = samples.samples;
    if (hierarchy.sample_order.size() != views.size())
        throw InvalidInput("cluster hierarchy", "built over " + std::to_string(hierarchy.sample_order.size()) +
                                                    " view samples, but " + std::to_string(views.size()) +
                                                    " were given");
    if (photons.photons.size() >= std::numeric_limits<uint32_t>::max())
        throw InvalidInput("photons", "too many photons for 32-bit photon indices");
    control.check();
    stats.bytes["hierarchy"] = double(hierarchy.bytes());
    for (const char* name : {"photon_node_tests", "photon_sample_tests", "contributing_pairs", "leaf_photon_pairs",
                             "splat_batches"})
        stats.counters[name] += 0.0;  // present even when there is nothing to splat
    if (hierarchy.empty() || photons.photons.empty()) {
        stats.bytes["leaf_photon_lists"] = 0.0;
        return std::vector<glm::vec3>(views.size(), glm::vec3(0.0f));  // (emitted may be 0: nothing to finish)
    }
    return ClusterSplat(hierarchy, samples, photons, params, control, stats).run();
}

}  // namespace ps
