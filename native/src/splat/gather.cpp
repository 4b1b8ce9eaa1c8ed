// Gathering from a hashed uniform grid of photons: the classic alternative to splatting (the "Hash Grid" of
// Mara et al. 2013), which the HPG 2016 paper argues against. Two steps:
//   1. build: photons (camera-relative, as every method splats them) are given integer cell coordinates on a
//      uniform grid of cell size h = r, sorted by (cell key, photon index) and copied into one contiguous array,
//      cell after cell, ascending photon index within a cell. The non-empty cells go into an open-addressing
//      hash table (linear probing, a power of two >= 2 × the cells) from the 63-bit cell key to the cell's range
//      of that array.
//   2. shade: each view sample (in parallel, in pixel order) visits the cells its sphere's bounding box
//      overlaps, runs the per-sample test of splat.h on their photons and adds up the contributions of those
//      that pass in ascending photon index: the same photons in the same order as `brute`, so the result is the
//      same bit for bit (unless the compiler orders the arithmetic of the shared inline functions differently).
//
// Rows. The key is (z << 42) | (y << 21) | x, so the cells x0..x1 of one (y, z) row are consecutive keys and,
// the photons being sorted by key, their photons are one contiguous range of the array.
//
// Order. Within a cell the photons ascend, but a sample's photons come from several cells. The photons of a
// cell range are merged into one list in ascending index (a bottom-up merge of the cells' runs), and that list
// is kept per thread and reused by the next samples for as long as their cell range is the same: neighbouring
// pixels mostly share it, so ordering costs a merge per list rather than a sort per sample (docs/benchmarks.md,
// "Gather's design", has the measurement against a sort per sample and against no ordering at all).
//
// Cell size. h = r: a sphere overlaps 2–3 cells per axis, a tested volume of ~27 r³; smaller cells test less but
// change their range more often (more lists to merge) and have more runs to merge; larger ones test more. It was
// the fastest of r/2 to 2r (docs/benchmarks.md, "Gather's design").
//
// No photon can be missed (the argument, since it is what makes the method exact). If a photon passes the test,
// then for each axis a the float d_a = x_a − p_a has fl(d_a²) <= dot(d, d) < fl(r·r) (a sum of non-negative
// rounded terms never rounds below one of them, with or without FMA contraction), so |d_a| < r, and as rounding
// is monotone the real x_a − r < p_a < x_a + r. The cell of a coordinate v is floor((v − lo) · inv_h) computed in
// double, a monotone function of v; the sample's cell range is that function at fl(x_a − r) <= p_a and at
// fl(x_a + r) >= p_a, clamped like the photon's. So the photon's cell is always in the range.
//
// Huge and tiny radii. A radius larger than the scene gives one cell per axis (every sample tests all photons,
// as brute does, but still in order and correct). A radius tiny against the photons' extent would need more
// cells per axis than 21 bits of key hold: the cell size of that axis is then raised to extent / (2^21 − 1),
// which only costs speed, and coordinates are clamped to the grid in any case, so nothing can overflow.
// Photons whose relative position is not finite can pass no per-sample test and are left out of the grid.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "photonsplat/errors.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/validation.h"
#include "photonsplat/splatter.h"

namespace ps {
namespace {

// Cell edge in kernel radii (see "Cell size" above).
constexpr double kCellSizeInRadii = 1.0;
constexpr int kKeyBitsPerAxis = 21;
constexpr int64_t kMaxCellsPerAxis = int64_t(1) << kKeyBitsPerAxis;
constexpr uint64_t kEmptyKey = ~uint64_t(0);  // no cell has it: real keys use 63 bits
// Samples per task: few enough for prompt cancels and balanced threads, enough to amortise a task.
constexpr size_t kSamplesPerTask = 64;
// Within one sample or one list (as large as all photons when the radius is larger than the scene): a cancel
// check this often.
constexpr uint32_t kPhotonsPerCancelCheck = 1 << 16;
// Merge buffers of a list longer than this are released once it is built (lists that long come from radii
// near the scene's size, whose cell range rarely changes): a thread then keeps 4 bytes per photon of it.
constexpr size_t kKeptMergeEntries = 1 << 16;

// A photon as the grid stores it: what the per-sample test and the contribution read, next to each other.
struct GridPhoton {
    glm::vec3 position;  // relative to the view samples' origin
    uint32_t index;      // in the photon map: the order contributions are added in
    Photon photon;
};

struct Cell {
    uint64_t key = kEmptyKey;
    uint32_t begin = 0, end = 0;  // its photons: GridPhoton range in the grid's array
};

uint64_t cell_key(int64_t x, int64_t y, int64_t z) {
    return (uint64_t(z) << (2 * kKeyBitsPerAxis)) | (uint64_t(y) << kKeyBitsPerAxis) | uint64_t(x);
}

// Fibonacci hashing: neighbouring keys (which differ in their low bits) land far apart.
size_t hash_slot(uint64_t key, int shift) { return size_t((key * 0x9E3779B97F4A7C15ull) >> shift); }

class PhotonGrid {
public:
    PhotonGrid(const std::vector<glm::vec3>& positions, const std::vector<Photon>& photons, float radius,
               const RenderControl& control) {
        // Bounds of the photons that can reach a sample at all.
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
        size_t valid = 0;
        for (const glm::vec3& p : positions)
            if (is_finite(p)) {
                lo = glm::min(lo, p);
                hi = glm::max(hi, p);
                ++valid;
            }
        const double h = kCellSizeInRadii * double(radius);
        for (int a = 0; a < 3; ++a) {
            origin_[a] = valid ? double(lo[a]) : 0.0;
            const double extent = valid ? double(hi[a]) - double(lo[a]) : 0.0;
            inv_h_[a] = 1.0 / h;  // finite: h >= the smallest float denormal
            if (extent * inv_h_[a] > double(kMaxCellsPerAxis - 1)) inv_h_[a] = double(kMaxCellsPerAxis - 1) / extent;
            cells_[a] = std::min<int64_t>(kMaxCellsPerAxis, int64_t(std::floor(extent * inv_h_[a])) + 1);
        }
        control.check();

        // (key, photon index) pairs, sorted: cells in key order, photons ascending within each.
        struct Entry {
            uint64_t key;
            uint32_t index;
            bool operator<(const Entry& o) const { return key != o.key ? key < o.key : index < o.index; }
        };
        std::vector<Entry> entries;
        entries.reserve(valid);
        for (size_t j = 0; j < positions.size(); ++j) {
            const glm::vec3& p = positions[j];
            if (!is_finite(p)) continue;
            int64_t c[3];
            for (int a = 0; a < 3; ++a) {
                const double f = cell_coordinate(a, double(p[a]));
                c[a] = int64_t(std::clamp(f, 0.0, double(cells_[a] - 1)));
            }
            entries.push_back({cell_key(c[0], c[1], c[2]), uint32_t(j)});
        }
        tbb::parallel_sort(entries.begin(), entries.end());
        control.check();

        photons_.resize(entries.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, entries.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t k = r.begin(); k != r.end(); ++k) {
                const uint32_t j = entries[k].index;
                photons_[k] = GridPhoton{positions[j], j, photons[j]};
            }
        });
        size_t cell_count = 0;
        for (size_t k = 0; k < entries.size(); ++k) cell_count += (k == 0 || entries[k].key != entries[k - 1].key);
        cell_count_ = cell_count;

        // Open addressing, linear probing, load factor <= 1/2.
        int bits = 4;
        while ((size_t(1) << bits) < 2 * cell_count) ++bits;
        shift_ = 64 - bits;
        mask_ = (size_t(1) << bits) - 1;
        table_.assign(size_t(1) << bits, Cell{});
        for (size_t k = 0; k < entries.size();) {
            size_t end = k + 1;
            while (end < entries.size() && entries[end].key == entries[k].key) ++end;
            size_t slot = hash_slot(entries[k].key, shift_);
            while (table_[slot].key != kEmptyKey) slot = (slot + 1) & mask_;
            table_[slot] = Cell{entries[k].key, uint32_t(k), uint32_t(end)};
            k = end;
        }
    }

    // floor((v − lo) · inv_h) on axis a: monotone in v (see the top of the file). May be out of the grid.
    double cell_coordinate(int a, double v) const { return std::floor((v - origin_[a]) * inv_h_[a]); }

    // The cells [first, last] per axis that a sphere of radius r around x can reach; false when none can.
    bool cell_range(const glm::vec3& x, float r, int64_t first[3], int64_t last[3]) const {
        for (int a = 0; a < 3; ++a) {
            const double f = cell_coordinate(a, double(x[a]) - double(r));
            const double l = cell_coordinate(a, double(x[a]) + double(r));
            if (!(l >= 0.0 && f <= double(cells_[a] - 1))) return false;  // also a NaN or infinite sample
            first[a] = int64_t(std::max(f, 0.0));
            last[a] = int64_t(std::min(l, double(cells_[a] - 1)));
        }
        return true;
    }

    const Cell* find(uint64_t key) const {
        for (size_t slot = hash_slot(key, shift_);; slot = (slot + 1) & mask_) {
            const Cell& cell = table_[slot];
            if (cell.key == key) return &cell;
            if (cell.key == kEmptyKey) return nullptr;
        }
    }

    const std::vector<GridPhoton>& photons() const { return photons_; }
    size_t cell_count() const { return cell_count_; }
    size_t bytes() const { return photons_.capacity() * sizeof(GridPhoton) + table_.capacity() * sizeof(Cell); }

private:
    double origin_[3] = {0, 0, 0};
    double inv_h_[3] = {1, 1, 1};
    int64_t cells_[3] = {1, 1, 1};
    std::vector<GridPhoton> photons_;
    std::vector<Cell> table_;
    size_t mask_ = 0;
    int shift_ = 60;
    size_t cell_count_ = 0;
};

struct Counts {
    uint64_t tests = 0, contributing = 0, cell_visits = 0, lists = 0;
};

// The photons of the cells [first, last], in ascending photon index: what every sample whose sphere has that
// cell range tests. Neighbouring samples mostly share their range (it changes when the sphere crosses a cell
// boundary: every ~h/2 of movement), so a thread keeps the list of its last range and rebuilds it only when
// the range changes; the ordering is then paid once per list, not once per sample. A list depends only on the
// range, never on which thread built it or what it held before.
class CandidateList {
public:
    void update(const PhotonGrid& grid, const int64_t first[3], const int64_t last[3], const RenderControl& control,
                Counts& counts) {
        if (valid_ && std::equal(first, first + 3, first_) && std::equal(last, last + 3, last_)) return;
        valid_ = false;  // until built: a cancel may stop the build halfway
        const std::vector<GridPhoton>& photons = grid.photons();
        // (photon index << 32) | position in the grid's array, in runs of ascending entries: within a cell they
        // ascend, and a new run starts wherever the next entry is smaller than the last.
        entries_.clear();
        runs_.assign(1, 0);
        cells_ = 0;
        uint64_t previous = 0;
        for (int64_t z = first[2]; z <= last[2]; ++z)
            for (int64_t y = first[1]; y <= last[1]; ++y) {
                // The row's cells are consecutive keys, so their photons are one range of the array.
                uint32_t begin = std::numeric_limits<uint32_t>::max(), end = 0;
                for (int64_t x = first[0]; x <= last[0]; ++x)
                    if (const Cell* cell = grid.find(cell_key(x, y, z))) {
                        begin = std::min(begin, cell->begin);
                        end = std::max(end, cell->end);
                        ++cells_;
                    }
                if (begin >= end) continue;
                if (end - begin > kPhotonsPerCancelCheck) control.check();
                for (uint32_t k = begin; k != end; ++k) {
                    const uint64_t entry = (uint64_t(photons[k].index) << 32) | k;
                    if (entry < previous) runs_.push_back(uint32_t(entries_.size()));
                    previous = entry;
                    entries_.push_back(entry);
                }
            }
        runs_.push_back(uint32_t(entries_.size()));
        merge_runs(control);
        slots_.resize(entries_.size());
        for (size_t k = 0; k < entries_.size(); ++k) slots_[k] = uint32_t(entries_[k]);
        if (entries_.capacity() > kKeptMergeEntries) {
            entries_ = std::vector<uint64_t>();
            other_ = std::vector<uint64_t>();
        }
        std::copy(first, first + 3, first_);
        std::copy(last, last + 3, last_);
        valid_ = true;
        ++counts.lists;
    }

    const std::vector<uint32_t>& slots() const { return slots_; }  // positions in the grid's array
    uint64_t cells() const { return cells_; }                       // non-empty cells in the range
    size_t bytes() const {
        return (entries_.capacity() + other_.capacity()) * sizeof(uint64_t) +
               (runs_.capacity() + other_runs_.capacity() + slots_.capacity()) * sizeof(uint32_t);
    }

private:
    // Bottom-up merge of adjacent runs, ping-ponging between two buffers: n log(runs).
    void merge_runs(const RenderControl& control) {
        const size_t n = entries_.size();
        if (runs_.size() <= 2) return;
        other_.resize(n);
        while (runs_.size() > 2) {
            if (n > kPhotonsPerCancelCheck) control.check();
            other_runs_.assign(1, 0);
            size_t r = 0;
            for (; r + 2 < runs_.size(); r += 2) {
                merge(entries_.data() + runs_[r], entries_.data() + runs_[r + 1], entries_.data() + runs_[r + 2],
                      other_.data() + runs_[r]);
                other_runs_.push_back(runs_[r + 2]);
            }
            if (r + 1 < runs_.size()) {  // an odd run out: carried over as it is
                std::copy(entries_.begin() + runs_[r], entries_.begin() + runs_[r + 1], other_.begin() + runs_[r]);
                other_runs_.push_back(runs_[r + 1]);
            }
            entries_.swap(other_);
            runs_.swap(other_runs_);
        }
    }

    // Merges the ascending ranges [a, mid) and [mid, end) into out. Entries are distinct, and which one comes
    // next is unpredictable: the choice is made with selects rather than branches.
    static void merge(const uint64_t* a, const uint64_t* mid, const uint64_t* end, uint64_t* out) {
        const size_t na = size_t(mid - a), nb = size_t(end - mid);
        const uint64_t* b = mid;
        size_t i = 0, j = 0;
        while (i < na && j < nb) {
            const uint64_t x = a[i], y = b[j];
            const size_t take_b = size_t(y < x);
            *out++ = take_b ? y : x;
            i += 1 - take_b;
            j += take_b;
        }
        out = std::copy(a + i, mid, out);
        std::copy(b + j, end, out);
    }

    bool valid_ = false;
    int64_t first_[3] = {0, 0, 0}, last_[3] = {0, 0, 0};
    uint64_t cells_ = 0;
    std::vector<uint64_t> entries_, other_;
    std::vector<uint32_t> runs_, other_runs_;
    std::vector<uint32_t> slots_;
};

struct Scratch {
    CandidateList list;
    std::vector<uint32_t> near;  // candidates that passed the distance pre-test
};

// Σ f_r·Φ·w over the photons that reach sample s, in ascending photon index.
//
// Two passes per block of candidates. The first is free of branches: a conservative distance pre-test (the
// per-sample test's own expression, against r² enlarged by a relative 1e-5 so that a different contraction of
// the same expression cannot make it stricter) compacts the candidates that may pass; about two in three do
// not, and a branch on that would be mispredicted most of the time. The second runs the real per-sample test
// on those, in the same (ascending) order, and adds up their contributions.
glm::dvec3 gather_sample(const PhotonGrid& grid, const ViewSample& s, const Lobe* lobes, const SplatParams& params,
                         float pretest_distance_sq, const RenderControl& control, Scratch& scratch, Counts& counts) {
    int64_t first[3], last[3];
    if (!grid.cell_range(s.position, params.radius, first, last)) return glm::dvec3(0.0);
    scratch.list.update(grid, first, last, control, counts);
    const std::vector<GridPhoton>& photons = grid.photons();
    const std::vector<uint32_t>& slots = scratch.list.slots();
    counts.cell_visits += scratch.list.cells();
    counts.tests += slots.size();
    const size_t block_size = std::min<size_t>(slots.size(), kPhotonsPerCancelCheck);
    if (scratch.near.size() < block_size) scratch.near.resize(block_size);
    uint32_t* near = scratch.near.data();
    glm::dvec3 reflected_flux(0.0);
    for (size_t block = 0; block < slots.size(); block += block_size) {
        if (block != 0) control.check();
        const size_t block_end = std::min(slots.size(), block + block_size);
        size_t n = 0;
        for (size_t k = block; k != block_end; ++k) {
            const uint32_t slot = slots[k];
            const glm::vec3 d = s.position - photons[slot].position;
            near[n] = slot;
            n += glm::dot(d, d) < pretest_distance_sq ? 1 : 0;
        }
        for (size_t i = 0; i != n; ++i) {
            const GridPhoton& g = photons[near[i]];
            if (!photon_reaches_sample(s, g.position, g.photon, params)) continue;
            reflected_flux += photon_reflected_flux(s, lobes, g.position, g.photon, params);
            ++counts.contributing;
        }
    }
    return reflected_flux;
}

}  // namespace

std::vector<glm::vec3> splat_gather(const ViewSamples& samples, const PhotonMap& photons, const SplatParams& params,
                                    const RenderControl& control, Stats& stats) {
    validate(params, photons);
    if (photons.photons.size() >= std::numeric_limits<uint32_t>::max())
        throw InvalidInput("photons", "too many photons for 32-bit photon indices");
    control.check();
    const std::vector<ViewSample>& views = samples.samples;
    std::vector<glm::vec3> radiance(views.size(), glm::vec3(0.0f));
    for (const char* name : {"photon_sample_tests", "contributing_pairs", "grid_cells", "cell_visits", "gather_lists"})
        stats.counters[name] += 0.0;  // present even when there is nothing to splat
    stats.bytes["photon_grid"] += 0.0;
    stats.bytes["gather_lists"] += 0.0;
    if (views.empty() || photons.photons.empty()) return radiance;  // as brute: (emitted may be 0)

    const PhotonGrid grid = [&] {
        StageTimer timer(stats, "splat_build_grid");
        return PhotonGrid(relative_photon_positions(photons, samples.origin), photons.photons, params.radius,
                          control);
    }();
    stats.counters["grid_cells"] += double(grid.cell_count());
    stats.bytes["photon_grid"] = double(grid.bytes());
    control.check();

    StageTimer timer(stats, "splat_shade");
    std::atomic<uint64_t> tests{0}, contributing{0}, cell_visits{0}, lists{0}, done{0};
    const float r = params.radius;
    const float pretest_distance_sq = r * r * (1.0f + 1e-5f);
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, views.size(), kSamplesPerTask),
                      [&](const tbb::blocked_range<size_t>& range) {
                          control.check();
                          Scratch& local = scratch.local();
                          Counts counts;
                          for (size_t i = range.begin(); i != range.end(); ++i) {
                              const ViewSample& s = views[i];
                              const glm::dvec3 reflected_flux =
                                  gather_sample(grid, s, samples.lobes.data(), params, pretest_distance_sq, control, local, counts);
                              radiance[i] = finish_sample(s, reflected_flux, params);
                          }
                          tests += counts.tests;
                          contributing += counts.contributing;
                          cell_visits += counts.cell_visits;
                          lists += counts.lists;
                          control.advance(done += range.size(), views.size());
                      });
    size_t list_bytes = 0;
    for (const Scratch& local : scratch) list_bytes += local.list.bytes() + local.near.capacity() * sizeof(uint32_t);
    stats.counters["photon_sample_tests"] += double(tests.load());
    stats.counters["contributing_pairs"] += double(contributing.load());
    stats.counters["cell_visits"] += double(cell_visits.load());
    // Candidate lists built, and what the threads' lists hold at the end. Unlike the other counters these depend
    // on how the samples fell to the threads (a thread's first sample of a task may or may not reuse its list).
    stats.counters["gather_lists"] += double(lists.load());
    stats.bytes["gather_lists"] = double(list_bytes);
    return radiance;
}


namespace {

class GatherSplatter final : public SampleSplatter {
public:
    GatherSplatter() : SampleSplatter(splat_gather) {}
    SplatMemory predict_memory(const SplatFrame& frame, size_t photons, const SplatParams&) const override {
        const double p = double(photons);
        SplatMemory m;
        // Grid photons (position, index, record), the sort entries they are made from, the hash table (at most
        // 2 cells per photon rounded up to a power of two: 4 × 16 bytes a photon), the positions.
        m.fixed["photon_grid"] = p * double(sizeof(glm::vec3) + 4 + sizeof(Photon)) + p * 4.0 * 16.0;
        m.fixed["photon_positions"] = photon_position_bytes(photons) + p * 16.0;
        // Each thread's candidate list and near list hold at most every photon once.
        m.fixed["gather_lists"] = double(std::max(frame.threads, 1)) * std::min(p, 65536.0) * 16.0;
        return m;
    }
};

}  // namespace

std::unique_ptr<Splatter> make_gather_splatter(const RenderSettings&) { return std::make_unique<GatherSplatter>(); }

}  // namespace ps
