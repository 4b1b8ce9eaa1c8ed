#include "photonsplat/photon_density.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/scattering.h"
#include "photonsplat/stats.h"
#include "photonsplat/validation.h"

namespace ps {

namespace {

constexpr uint64_t kAxisCells = 1ull << 20;  // cells per axis at most (keys hold 21 bits an axis, with margin)
constexpr size_t kTypicalSample = 65536;     // photons the typical number is taken from, at most

uint64_t pack(uint64_t x, uint64_t y, uint64_t z) { return (z << 42) | (y << 21) | x; }

size_t table_capacity(size_t photons) {
    size_t capacity = 16;
    while (capacity < 2 * photons) capacity *= 2;
    return capacity;
}

// What a cell (or a box of cells) holds: its photons, and the sums of their weights (power's luminance) and of
// their squares, whose ratio (Σw)² / Σw² is the number of equal photons as noisy as they are.
struct Tally {
    uint32_t count = 0;
    float weight = 0.0f, weight_squared = 0.0f;
    void add(const Tally& t) {
        count += t.count;
        weight += t.weight;
        weight_squared += t.weight_squared;
    }
    double effective() const {
        return weight_squared > 0.0f ? double(weight) * double(weight) / double(weight_squared) : 0.0;
    }
};

// Tallies per cell: an open-addressing table (linear probing) from a cell's packed coordinates.
class CellTallies {
public:
    explicit CellTallies(size_t photons) {
        const size_t capacity = table_capacity(photons);
        keys_.assign(capacity, kEmpty);
        tallies_.assign(capacity, Tally{});
        mask_ = capacity - 1;
        while ((size_t(1) << bits_) < capacity) ++bits_;
    }
    void add(uint64_t key, const Tally& t) { tallies_[slot(key)].add(t); }
    Tally tally(uint64_t key) const {
        for (size_t i = hash(key);; i = (i + 1) & mask_) {
            if (keys_[i] == key) return tallies_[i];
            if (keys_[i] == kEmpty) return Tally{};
        }
    }
    size_t bytes() const { return keys_.capacity() * sizeof(uint64_t) + tallies_.capacity() * sizeof(Tally); }

private:
    static constexpr uint64_t kEmpty = ~0ull;
    // Fibonacci hashing: the product's top bits depend on every bit of the key (all three axes).
    size_t hash(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits_)); }
    size_t slot(uint64_t key) {
        for (size_t i = hash(key);; i = (i + 1) & mask_) {
            if (keys_[i] == key) return i;
            if (keys_[i] == kEmpty) {
                keys_[i] = key;
                return i;
            }
        }
    }
    std::vector<uint64_t> keys_;
    std::vector<Tally> tallies_;
    size_t mask_ = 0;
    int bits_ = 0;
};

bool finite(const Photon& p) { return is_finite(p.position); }

// The grid the tallies are taken on: cells of the radius's size (wider along an axis whose extent would need more
// than kAxisCells), from the finite photons' lower corner; coordinates are offset by one so that the cell below
// the first is 0.
struct Grid {
    glm::dvec3 lo, cell;
    uint64_t coordinate(const glm::vec3& position, double shift, int a) const {
        const double v = std::floor((double(position[a]) - lo[a]) / cell[a] - shift) + 1.0;
        return static_cast<uint64_t>(std::clamp(v, 0.0, double(kAxisCells)));
    }
    uint64_t cell_of(const glm::vec3& q) const {
        return pack(coordinate(q, 0.0, 0), coordinate(q, 0.0, 1), coordinate(q, 0.0, 2));
    }
};

Tally tally_of(const Photon& p) {
    const float w = luminance(p.power);
    const float weight = std::isfinite(w) ? std::max(w, 0.0f) : 0.0f;
    return Tally{1u, weight, weight * weight};
}

// The photons of `subset` (indices into `photons`, finite ones) tallied per cell, then each one's box: the 2 × 2 × 2
// cells whose centres are nearest it. Both passes follow the map's Morton order: runs of photons in one cell are
// added at once, and consecutive photons mostly share their box, whose tally is kept until it changes.
std::vector<Tally> box_tallies(const std::vector<Photon>& photons, const std::vector<uint32_t>& subset,
                               const Grid& grid, double& bytes) {
    CellTallies cells(subset.size());
    uint64_t run_key = 0;
    Tally run;
    for (uint32_t i : subset) {
        const uint64_t key = grid.cell_of(photons[i].position);
        if (run.count > 0 && key != run_key) cells.add(run_key, run), run = Tally{};
        run_key = key;
        run.add(tally_of(photons[i]));
    }
    if (run.count > 0) cells.add(run_key, run);
    std::vector<Tally> boxes(subset.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, subset.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        uint64_t last = ~0ull;
        Tally box;
        for (size_t j = r.begin(); j != r.end(); ++j) {
            const glm::vec3& q = photons[subset[j]].position;
            const uint64_t x = grid.coordinate(q, 0.5, 0), y = grid.coordinate(q, 0.5, 1), z = grid.coordinate(q, 0.5, 2);
            const uint64_t key = pack(x, y, z);
            if (key != last) {
                box = Tally{};
                for (int c = 0; c < 8; ++c) box.add(cells.tally(pack(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2))));
                last = key;
            }
            boxes[j] = box;
        }
    });
    bytes += double(cells.bytes()) + double(boxes.capacity()) * sizeof(Tally);
    return boxes;
}

// The median of the boxes' effective counts over the surface they light: each weighing 1 / its box's count, the
// area its photon stands for. Summed in sorted order: the same figure whatever the threads.
double area_median(std::vector<Tally> boxes) {
    std::sort(boxes.begin(), boxes.end(), [](const Tally& a, const Tally& b) { return a.effective() < b.effective(); });
    double area = 0.0;
    for (const Tally& t : boxes) area += t.count > 0 ? 1.0 / t.count : 0.0;
    double below = 0.0;
    for (const Tally& t : boxes) {
        below += t.count > 0 ? 1.0 / t.count : 0.0;
        if (below >= 0.5 * area) return t.effective();
    }
    return 0.0;
}

}  // namespace

double predict_radius_level_bytes(size_t photons) {
    // The candidates' and the sample's indices, tables and boxes, and the levels.
    const size_t sample = std::min(photons, kTypicalSample);
    return double(table_capacity(photons) + table_capacity(sample)) * (sizeof(uint64_t) + sizeof(Tally)) +
           double(photons + sample) * (sizeof(uint32_t) + sizeof(Tally)) + double(photons);
}

RadiusLevels photon_radius_levels(const PhotonMap& map, float radius, Stats& stats) {
    const std::vector<Photon>& photons = map.photons;
    RadiusLevels out;
    out.level.assign(photons.size(), 0);
    out.count[0] = photons.size();
    if (!(radius > 0.0f) || !std::isfinite(radius)) return out;
    const auto candidate = [&](size_t i) { return (photons[i].flags & kAfterGlossy) && finite(photons[i]); };
    size_t candidate_count = 0;
    for (size_t i = 0; i < photons.size(); ++i) candidate_count += candidate(i) ? 1 : 0;
    if (candidate_count == 0) return out;  // nothing a glossy or sharp part could have focused
    std::vector<uint32_t> candidates, sample;
    candidates.reserve(candidate_count);
    for (size_t i = 0; i < photons.size(); ++i)
        if (candidate(i)) candidates.push_back(static_cast<uint32_t>(i));

    Grid grid;
    grid.lo = glm::dvec3(std::numeric_limits<double>::infinity());
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    for (const Photon& p : photons) {
        if (!finite(p)) continue;
        grid.lo = glm::min(grid.lo, glm::dvec3(p.position));
        hi = glm::max(hi, glm::dvec3(p.position));
    }
    for (int a = 0; a < 3; ++a) grid.cell[a] = std::max(double(radius), (hi[a] - grid.lo[a]) / double(kAxisCells - 4));

    // The typical number, from every stride-th finite photon (their numbers times the stride).
    const size_t stride = (photons.size() + kTypicalSample - 1) / kTypicalSample;
    sample.reserve((photons.size() + stride - 1) / stride);
    for (size_t i = 0; i < photons.size(); i += stride)
        if (finite(photons[i])) sample.push_back(static_cast<uint32_t>(i));
    double bytes = double(candidates.capacity() + sample.capacity()) * sizeof(uint32_t);
    out.typical = double(stride) * area_median(box_tallies(photons, sample, grid, bytes));

    // The candidates' numbers among themselves: a level's splat holds only its own photons.
    const std::vector<Tally> boxes = box_tallies(photons, candidates, grid, bytes);
    const double base = std::max(out.typical, kMinTypicalCount);
    for (size_t j = 0; j < candidates.size(); ++j) {
        int k = 0;
        while (k + 1 < kRadiusLevels && boxes[j].effective() >= base * double(1u << (2 * (k + 1)))) ++k;
        out.level[candidates[j]] = static_cast<uint8_t>(k);
        --out.count[0];
        ++out.count[k];
    }
    stats.bytes["radius_levels"] = bytes + double(out.level.capacity());
    stats.values["typical_photon_count"] = out.typical;
    return out;
}

}  // namespace ps
