// Splatting with screen tiles, after Mara, Luebke and McGuire, "Toward Practical Real-Time Photon Mapping:
// Efficient GPU Density Estimation" (I3D 2013), on the CPU, in three steps:
//   1. tiles: the image is cut into 32×32 pixel tiles. Each tile gets the view-space frustum of its pixel
//      rectangle (four planes through the eye; parallel planes for an orthographic camera) and the depth range
//      [z_min, z_max] of its view samples;
//   2. binning: each photon's sphere (radius r) is projected to a screen rectangle analytically (the tangent
//      planes through the eye; the whole screen when the sphere reaches the eye
//      plane), and every tile of that rectangle whose frustum planes and depth range the sphere meets gets a
//      (tile, photon) pair. A stable counting sort turns the pairs into one photon list per tile, photon indices
//      ascending;
//   3. shading: each tile shades its own samples from its own list (no two threads write one output), with the
//      per-sample test and contribution of splat.h, into a double sum per sample.
// Every sample thus sees the photons that can reach it in ascending index order, exactly as in `brute`: the
// output is the same bit for bit unless the compiler orders the arithmetic differently.
//
// Samples outside their pixel's frustum. A view sample seen through a mirror or glass (kViaSpecular) lies
// wherever its camera path ended, not on its pixel's ray, so the tile frustum says nothing about it. Rather
// than trust the flag, every sample is checked against its tile's frustum with the same plane distances the
// photons are tested with: those inside belong to the tile (and bound its depth range); those outside (mirror
// and glass samples, and any hand-made sample off its pixel's ray) go to a separate 3D structure. They are
// sorted by the Morton code of their position and cut into groups of kGroupSize, each with its box, under a
// small implicit tree of boxes (kTreeFanout children a node). Photons walk that tree (sphere vs box) and get a
// pair with every group they may reach; a group is then shaded like a tile, from its own list. A tile's own
// samples and its outside samples never share a list, so the (usually wide) spread of mirror samples does not
// make the tile's ordinary samples test more photons.
//
// Conservative in float. A sample counts as inside when its four plane distances, computed in float, are >= 0.
// A photon keeps a tile when its own distances are >= −(r + m) and its depth is within r + m of the range, with
// m = 1e-5·(r + |p − eye|₁ + largest plane offset): far more than the rounding of both dot products and of
// |x − p|² < r². The analytic screen rectangle is computed in double for the radius r + 3m, so it contains every
// tile whose plane tests could pass. The box test rounds towards keeping, as the cluster method's does.
//
// Bounded memory. Pairs grow as photons × tiles touched: with a radius as large as the scene that is every
// photon in every tile (200k × 2040 at 1080p). So a first pass counts each photon's pairs, and keeps the pairs
// too while their total stays under SplatParams::max_pairs_in_memory (the cap); when it does (a typical radius),
// they are sorted into lists and shaded in one batch. When it does not, what was kept is dropped, the photons
// are cut into batches of consecutive indices whose pairs stay under the cap (at least one photon a batch), and
// each batch is binned again, sorted and shaded before the next, the per-sample sums carrying over between
// batches. Batches come in photon order and lists are ascending, so the result does not depend on the cut.
// Pairs held at once: at most the cap, plus one photon's pairs per thread while counting, or a batch of one
// photon whose pairs alone exceed the cap; 4 bytes each, twice (pairs, then lists), plus the growth slack of
// the chunks being counted.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "splat_inputs.h"
#include "photonsplat/validation.h"
#include "photonsplat/splatter.h"

#include "../building_blocks.h"

namespace ps {


namespace {

constexpr int kTileSize = 32;
constexpr size_t kPhotonsPerChunk = 512;     // binning work items (photons are independent: any split works)
constexpr size_t kGroupSize = 32;            // samples outside their tile's frustum: a group's size
constexpr size_t kTreeFanout = 8;            // children per node of the tree over those groups
constexpr double kRelativeMargin = 1e-5;     // see "Conservative in float" above
constexpr size_t kSamplesPerCancelCheck = 16;

using Range = tbb::blocked_range<size_t>;

// The camera as the tiles see it, derived from Camera::generate_ray alone: an orthonormal frame and where the
// pixel columns and rows lie. Perspective: pixel column px holds the points whose x/z in this frame is
// a0 + a_step·px, row py those whose y/z is b0 + b_step·py (a_step > 0, b_step < 0: y is up, py down).
// Orthographic: x = a0 + a_step·px and y = b0 + b_step·py themselves, relative to the camera position.
struct ViewFrame {
    bool orthographic = false;
    glm::dvec3 right{1.0, 0.0, 0.0}, up{0.0, 1.0, 0.0}, forward{0.0, 0.0, 1.0};
    double a0 = 0.0, a_step = 1.0, b0 = 0.0, b_step = -1.0;
};

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

ViewFrame view_frame(const Camera& camera) {
    const double w = camera.width(), h = camera.height();
    const glm::dvec3 eye(camera.position());
    auto direction = [&](double px, double py) {
        return glm::dvec3(camera.generate_ray(float(px), float(py)).direction);
    };
    auto ray_origin = [&](double px, double py) {  // relative to the camera position
        return glm::dvec3(camera.generate_ray(float(px), float(py)).origin) - eye;
    };
    ViewFrame f;
    f.orthographic = camera.orthographic();
    glm::dvec3 right, up;
    if (f.orthographic) {
        f.forward = glm::normalize(direction(0.5 * w, 0.5 * h));
        right = ray_origin(w, 0.5 * h) - ray_origin(0.0, 0.5 * h);
        up = ray_origin(0.5 * w, 0.0) - ray_origin(0.5 * w, h);
    } else {
        // Every plane through the eye that holds a pixel column holds the up axis, and every one that holds a
        // pixel row the right axis (the projection has no skew): intersect the image's edge planes.
        const glm::dvec3 left_edge = glm::cross(direction(0.0, 0.0), direction(0.0, h));
        const glm::dvec3 right_edge = glm::cross(direction(w, 0.0), direction(w, h));
        const glm::dvec3 top_edge = glm::cross(direction(0.0, 0.0), direction(w, 0.0));
        const glm::dvec3 bottom_edge = glm::cross(direction(0.0, h), direction(w, h));
        up = glm::cross(left_edge, right_edge);
        right = glm::cross(top_edge, bottom_edge);
        f.forward = glm::cross(up, right);
        if (glm::dot(f.forward, direction(0.5 * w, 0.5 * h)) < 0.0) f.forward = -f.forward;
        f.forward = glm::normalize(f.forward);
    }
    // Gram–Schmidt, then orient right and up along increasing px and decreasing py.
    f.right = glm::normalize(right - glm::dot(right, f.forward) * f.forward);
    f.up = up - glm::dot(up, f.forward) * f.forward;
    f.up = glm::normalize(f.up - glm::dot(f.up, f.right) * f.right);
    auto column_coordinate = [&](double px) {
        if (f.orthographic) return glm::dot(ray_origin(px, 0.5 * h), f.right);
        const glm::dvec3 d = direction(px, 0.5 * h);
        return glm::dot(d, f.right) / glm::dot(d, f.forward);
    };
    auto row_coordinate = [&](double py) {
        if (f.orthographic) return glm::dot(ray_origin(0.5 * w, py), f.up);
        const glm::dvec3 d = direction(0.5 * w, py);
        return glm::dot(d, f.up) / glm::dot(d, f.forward);
    };
    if (column_coordinate(w) < column_coordinate(0.0)) f.right = -f.right;
    if (row_coordinate(h) > row_coordinate(0.0)) f.up = -f.up;
    f.a0 = column_coordinate(0.0);
    f.a_step = (column_coordinate(w) - f.a0) / w;
    f.b0 = row_coordinate(0.0);
    f.b_step = (row_coordinate(h) - f.b0) / h;
    if (!finite(f.right) || !finite(f.up) || !finite(f.forward) || !(f.a_step > 0.0) || !(f.b_step < 0.0) ||
        !std::isfinite(f.a0) || !std::isfinite(f.b0) || !std::isfinite(f.a_step) || !std::isfinite(f.b_step))
        throw InvalidInput("camera", "its rays do not span a usable image plane (tiled splat)");
    return f;
}

// Pixel rectangle of a sphere (centre q relative to the eye, in world axes): see tiled_sphere_screen_bounds.
// Perspective: the tangent planes through the eye that hold the frame's up axis bound x/z by
// m± = (x z ± R √(x² + z² − R²)) / (z² − R²), likewise y/z; those slopes are then mapped to pixels.
glm::dvec4 sphere_screen_rect(const ViewFrame& f, const glm::dvec3& q, double radius) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const double x = glm::dot(q, f.right), y = glm::dot(q, f.up), z = glm::dot(q, f.forward);
    double x_lo, x_hi, y_lo, y_hi;
    if (f.orthographic) {
        x_lo = x - radius, x_hi = x + radius;
        y_lo = y - radius, y_hi = y + radius;
    } else {
        if (!(z > radius)) return glm::dvec4(-inf, -inf, inf, inf);  // reaches the eye plane (or NaN)
        const double den = (z - radius) * (z + radius);
        const double sx = radius * std::sqrt(x * x + den), sy = radius * std::sqrt(y * y + den);
        x_lo = (x * z - sx) / den, x_hi = (x * z + sx) / den;
        y_lo = (y * z - sy) / den, y_hi = (y * z + sy) / den;
    }
    const double px0 = (x_lo - f.a0) / f.a_step, px1 = (x_hi - f.a0) / f.a_step;
    const double py0 = (y_hi - f.b0) / f.b_step, py1 = (y_lo - f.b0) / f.b_step;  // b_step < 0
    if (std::isnan(px0) || std::isnan(px1) || std::isnan(py0) || std::isnan(py1))
        return glm::dvec4(-inf, -inf, inf, inf);
    return glm::dvec4(px0, py0, px1, py1);
}

// A plane with unit normal: signed distance dot(n, q) − d, q relative to the eye.
struct Plane {
    glm::vec3 n;
    float d;
    float distance(const glm::vec3& q) const { return glm::dot(n, q) - d; }
};

// Per tile: the depth range of its samples inside its frustum.
struct TileBounds {
    float z_min = std::numeric_limits<float>::infinity();
    float z_max = -std::numeric_limits<float>::infinity();
    uint32_t inside = 0;  // samples inside the frustum (with a finite position)
};

// The 30-bit Morton code of p in the box (10 bits an axis).
uint32_t morton_code(const glm::vec3& p, const Box& box) {
    auto spread = [](uint32_t v) {  // 10 bits → every third bit
        v = (v | (v << 16)) & 0x030000FFu;
        v = (v | (v << 8)) & 0x0300F00Fu;
        v = (v | (v << 4)) & 0x030C30C3u;
        v = (v | (v << 2)) & 0x09249249u;
        return v;
    };
    const glm::vec3 extent = glm::max(box.hi - box.lo, glm::vec3(1e-30f));
    const glm::vec3 unit = glm::clamp((p - box.lo) / extent, glm::vec3(0.0f), glm::vec3(1.0f));
    const uint32_t x = uint32_t(unit.x * 1023.0f), y = uint32_t(unit.y * 1023.0f), z = uint32_t(unit.z * 1023.0f);
    return spread(x) | (spread(y) << 1) | (spread(z) << 2);
}

// Squared distance from p to the box, written with the same float operations as the per-sample test's
// dot(x − p, x − p): for x in the box each gap component is a correctly rounded difference no larger in
// magnitude than the rounded x − p on that axis, and squaring and summing are monotone, so this never exceeds
// the distance the per-sample test computes. The caller rejects only beyond r²·(1 + 1e-5), in case the compiler
// contracts one of the two expressions into FMAs.
[[gnu::always_inline]] inline float distance_sq_to_box(const glm::vec3& p, const Box& box) {
    const glm::vec3 gap = glm::max(glm::max(box.lo - p, p - box.hi), glm::vec3(0.0f));
    return glm::dot(gap, gap);
}

template <class T>
int64_t bytes_of(const std::vector<T>& v) {
    return int64_t(v.capacity() * sizeof(T));
}

class TiledSplat : private SplatInputs {
public:
    TiledSplat(const ViewSamples& samples, const Camera& camera, const PhotonMap& photons, const SplatParams& params,
               const RenderControl& control, Stats& stats)
        : SplatInputs(samples, photons, params, control, stats),
          frame_(view_frame(camera)),
          width_(camera.width()),
          height_(camera.height()),
          tiles_x_((width_ + kTileSize - 1) / kTileSize),
          tiles_y_((height_ + kTileSize - 1) / kTileSize),
          eye_(camera.position() - samples.origin),
          forward_(frame_.forward),
          radiance_(views_.size(), glm::vec3(0.0f)) {
        const float r = params.radius;
        reject_box_sq_ = (r * r) * (1.0f + 1e-5f);
        prefilter_sq_ = (r * r) * (1.0f + 1e-5f);
    }

    std::vector<glm::vec3> run() {
        {
            StageTimer timer(stats_, "splat_binning");
            build_tiles();
            count_pairs();
        }
        // Batches: consecutive photons whose pairs stay under the cap (at least one photon each).
        const size_t n = positions_.size();
        std::vector<size_t> batch_ends;
        size_t max_batch_photons = 0;
        uint64_t max_batch_pairs = 0;
        for (size_t begin = 0; begin < n;) {
            size_t end = begin;
            uint64_t pairs = 0;
            while (end < n && (end == begin || pairs + counts_[end] <= params_.max_pairs_in_memory))
                pairs += counts_[end++];
            batch_ends.push_back(end);
            max_batch_photons = std::max(max_batch_photons, end - begin);
            max_batch_pairs = std::max(max_batch_pairs, pairs);
            begin = end;
        }
        // The buffers are sized once, for the largest batch (the pairs kept by count_pairs stand in for the
        // per-photon offsets and pair buffer when there is one batch).
        if (!pairs_kept_) {
            photon_offsets_.reserve(max_batch_photons + 1);
            pair_tiles_.reserve(max_batch_pairs);
        }
        list_.reserve(max_batch_pairs);
        list_begin_.reserve(bin_count_ + 1);
        meter_.add(bytes_of(photon_offsets_) + bytes_of(pair_tiles_) + bytes_of(list_) + 2 * bytes_of(list_begin_));
        if (batch_ends.size() > 1) sums_.assign(views_.size(), glm::dvec3(0.0));

        size_t begin = 0;
        for (const size_t end : batch_ends) {
            control_.check();
            {
                StageTimer timer(stats_, "splat_binning");
                fill_lists(begin, end);
            }
            {
                StageTimer timer(stats_, "splat_shade");
                shade(end == n);
            }
            ++batches_;
            begin = end;
        }

        stats_.counters["photon_tile_tests"] += double(tile_tests_.load());
        stats_.counters["photon_sample_tests"] += double(sample_tests_.load());
        stats_.counters["contributing_pairs"] += double(contributing_.load());
        report_batches("tile", total_pairs_, batches_, double(meter_.peak()),
                       double(sums_.capacity() * sizeof(glm::dvec3)));
        return std::move(radiance_);
    }

private:
    // ---- 1. tiles ------------------------------------------------------------------------------------------
    void build_tiles() {
        const size_t tile_count = size_t(tiles_x_) * size_t(tiles_y_);
        // Boundary planes, positive towards increasing px (columns) and increasing py (rows).
        for (int k = 0; k <= tiles_x_; ++k) {
            const double px = std::min(k * kTileSize, width_);
            const double a = frame_.a0 + frame_.a_step * px;
            if (frame_.orthographic)
                columns_.push_back({glm::vec3(frame_.right), float(a)});
            else
                columns_.push_back({glm::vec3((frame_.right - a * frame_.forward) / std::sqrt(1.0 + a * a)), 0.0f});
        }
        for (int k = 0; k <= tiles_y_; ++k) {
            const double py = std::min(k * kTileSize, height_);
            const double b = frame_.b0 + frame_.b_step * py;
            if (frame_.orthographic)
                rows_.push_back({glm::vec3(-frame_.up), float(-b)});
            else
                rows_.push_back({glm::vec3((b * frame_.forward - frame_.up) / std::sqrt(1.0 + b * b)), 0.0f});
        }
        for (const std::vector<Plane>* planes : {&columns_, &rows_})
            for (const Plane& plane : *planes)
                max_plane_offset_ = std::max(max_plane_offset_, std::fabs(double(plane.d)));

        // Each sample's tile.
        const uint64_t pixels = uint64_t(width_) * uint64_t(height_);
        std::vector<uint32_t> sample_tile(views_.size());
        for (size_t i = 0; i < views_.size(); ++i) {
            const uint32_t pixel = views_[i].pixel;
            if (pixel >= pixels)
                throw InvalidInput("view samples", "sample " + std::to_string(i) + " has pixel " +
                                                       std::to_string(pixel) + ", outside the " +
                                                       std::to_string(width_) + "×" + std::to_string(height_) +
                                                       " image");
            const uint32_t x = pixel % uint32_t(width_), y = pixel / uint32_t(width_);
            sample_tile[i] = (y / kTileSize) * uint32_t(tiles_x_) + x / kTileSize;
        }
        // Inside or outside its tile's frustum (the same plane distances as the photons get), and the tiles'
        // depth ranges. A sample with a non-finite position passes no per-sample test: it stays with its tile,
        // for finish_sample, but bounds nothing.
        enum : uint8_t { kInside, kOutside, kNowhere };
        std::vector<uint8_t> kind(views_.size());
        tiles_.assign(tile_count, TileBounds());
        tbb::parallel_for(Range(0, views_.size(), 4096), [&](const Range& range) {
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const glm::vec3& x = views_[i].position;
                const int tx = int(sample_tile[i] % uint32_t(tiles_x_)), ty = int(sample_tile[i] / uint32_t(tiles_x_));
                const glm::vec3 q = x - eye_;
                if (!is_finite(x))
                    kind[i] = kNowhere;
                else if (columns_[tx].distance(q) >= 0.0f && columns_[tx + 1].distance(q) <= 0.0f &&
                         rows_[ty].distance(q) >= 0.0f && rows_[ty + 1].distance(q) <= 0.0f)
                    kind[i] = kInside;
                else
                    kind[i] = kOutside;
            }
        });
        control_.check();
        std::vector<uint32_t> outside;
        Box outside_box;
        for (size_t i = 0; i < views_.size(); ++i) {
            if (kind[i] == kOutside) {
                outside.push_back(uint32_t(i));
                outside_box.add(views_[i].position);
            } else if (kind[i] == kInside) {
                TileBounds& b = tiles_[sample_tile[i]];
                const float z = glm::dot(forward_, views_[i].position - eye_);
                b.z_min = std::min(b.z_min, z);
                b.z_max = std::max(b.z_max, z);
                ++b.inside;
            }
        }
        // Outside samples in Morton order (ties by index), cut into groups, and a tree of boxes over the groups.
        {
            std::vector<uint64_t> keys(outside.size());
            tbb::parallel_for(Range(0, outside.size(), 4096), [&](const Range& range) {
                for (size_t k = range.begin(); k != range.end(); ++k)
                    keys[k] = (uint64_t(morton_code(views_[outside[k]].position, outside_box)) << 32) | outside[k];
            });
            std::sort(keys.begin(), keys.end());
            for (size_t k = 0; k < keys.size(); ++k) outside[k] = uint32_t(keys[k] & 0xFFFFFFFFu);
        }
        group_count_ = (outside.size() + kGroupSize - 1) / kGroupSize;
        if (group_count_ > 0) {
            std::vector<Box> level(group_count_);
            for (size_t k = 0; k < outside.size(); ++k) level[k / kGroupSize].add(views_[outside[k]].position);
            levels_.push_back(std::move(level));
            while (levels_.back().size() > kTreeFanout) {
                const std::vector<Box>& below = levels_.back();
                std::vector<Box> above((below.size() + kTreeFanout - 1) / kTreeFanout);
                for (size_t k = 0; k < below.size(); ++k) above[k / kTreeFanout].add(below[k]);
                levels_.push_back(std::move(above));
            }
        }

        // The samples of every bin: bins [0, tiles) are the tiles (their samples inside, or nowhere; ascending),
        // bins [tiles, tiles + groups) the groups of outside samples.
        bin_count_ = tile_count + group_count_;
        bin_samples_begin_.assign(bin_count_ + 1, 0);
        for (size_t i = 0; i < views_.size(); ++i)
            if (kind[i] != kOutside) ++bin_samples_begin_[sample_tile[i] + 1];
        for (size_t t = 0; t < tile_count; ++t) bin_samples_begin_[t + 1] += bin_samples_begin_[t];
        for (size_t g = 0; g < group_count_; ++g)
            bin_samples_begin_[tile_count + g + 1] =
                bin_samples_begin_[tile_count] + uint32_t(std::min(outside.size(), (g + 1) * kGroupSize));
        bin_samples_.resize(views_.size());
        {
            std::vector<uint32_t> cursor(bin_samples_begin_.begin(), bin_samples_begin_.begin() + tile_count);
            for (size_t i = 0; i < views_.size(); ++i)
                if (kind[i] != kOutside) bin_samples_[cursor[sample_tile[i]]++] = uint32_t(i);
            std::copy(outside.begin(), outside.end(), bin_samples_.begin() + bin_samples_begin_[tile_count]);
        }

        size_t tree_boxes = 0;
        for (const std::vector<Box>& level : levels_) tree_boxes += level.capacity();
        stats_.bytes["tile_bounds"] = double(tiles_.capacity() * sizeof(TileBounds) +
                                             (columns_.capacity() + rows_.capacity()) * sizeof(Plane) +
                                             tree_boxes * sizeof(Box));
        stats_.bytes["tile_samples"] = double((bin_samples_.capacity() + bin_samples_begin_.capacity()) *
                                              sizeof(uint32_t));
        stats_.counters["tiles"] += double(tile_count);
        stats_.counters["outside_sample_groups"] += double(group_count_);
        stats_.counters["samples_outside_tile_frustum"] += double(outside.size());
    }

    // ---- 2. binning ----------------------------------------------------------------------------------------
    // Per-thread scratch of bin_photon.
    struct Scratch {
        std::vector<uint8_t> column_pass, row_pass;  // of the tile columns and rows of the screen rectangle
        std::vector<std::pair<uint32_t, uint32_t>> stack;  // (level, node) of the tree over outside groups
    };

    // Calls emit(bin) once for every bin photon j may reach; returns the sphere-vs-bound tests made.
    template <class Emit>
    uint64_t bin_photon(uint32_t j, Scratch& scratch, Emit&& emit) const {
        const glm::vec3& p = positions_[j];
        const glm::vec3 q = p - eye_;
        if (!is_finite(q)) return 0;  // passes no per-sample test (or lies beyond float range from the eye)
        const double r = params_.radius;
        const double margin =
            kRelativeMargin * (r + std::fabs(double(q.x)) + std::fabs(double(q.y)) + std::fabs(double(q.z)) +
                               max_plane_offset_);
        const float reach = float(r + margin);  // +inf when huge: then nothing is culled, which is safe
        uint64_t tests = 0;

        // Tiles of the analytic screen rectangle whose side planes and depth range the sphere meets.
        const glm::dvec4 rect = sphere_screen_rect(frame_, glm::dvec3(q), r + 3.0 * margin);
        int tx0, tx1, ty0, ty1;
        if (tile_range(rect.x, rect.z, width_, tiles_x_, tx0, tx1) &&
            tile_range(rect.y, rect.w, height_, tiles_y_, ty0, ty1)) {
            float lower = columns_[tx0].distance(q);  // the boundary on the tile's low side
            for (int tx = tx0; tx <= tx1; ++tx) {
                const float upper = columns_[tx + 1].distance(q);
                scratch.column_pass[tx] = lower >= -reach && upper <= reach;
                lower = upper;
            }
            lower = rows_[ty0].distance(q);
            for (int ty = ty0; ty <= ty1; ++ty) {
                const float upper = rows_[ty + 1].distance(q);
                scratch.row_pass[ty] = lower >= -reach && upper <= reach;
                lower = upper;
            }
            const float z = glm::dot(forward_, q);
            for (int ty = ty0; ty <= ty1; ++ty) {
                if (!scratch.row_pass[ty]) continue;
                for (int tx = tx0; tx <= tx1; ++tx) {
                    if (!scratch.column_pass[tx]) continue;
                    const size_t t = size_t(ty) * size_t(tiles_x_) + size_t(tx);
                    const TileBounds& b = tiles_[t];
                    if (b.inside == 0) continue;  // nothing to bound, nothing to test
                    ++tests;
                    if (z + reach >= b.z_min && z - reach <= b.z_max) emit(uint32_t(t));
                }
            }
        }
        // Groups of samples outside their tile's frustum, wherever they are on screen: down the tree of boxes.
        if (!levels_.empty()) {
            const uint32_t top = uint32_t(levels_.size() - 1);
            for (uint32_t k = uint32_t(levels_[top].size()); k-- > 0;) scratch.stack.push_back({top, k});
            while (!scratch.stack.empty()) {
                const auto [level, node] = scratch.stack.back();
                scratch.stack.pop_back();
                ++tests;
                if (distance_sq_to_box(p, levels_[level][node]) > reject_box_sq_) continue;
                if (level == 0) {
                    emit(uint32_t(tiles_.size() + node));
                    continue;
                }
                const uint32_t first = node * uint32_t(kTreeFanout);
                const uint32_t last = std::min(uint32_t(levels_[level - 1].size()), first + uint32_t(kTreeFanout));
                for (uint32_t c = last; c-- > first;) scratch.stack.push_back({level - 1, c});
            }
        }
        return tests;
    }

    // The tiles [t0, t1] whose pixels [32·t, 32·t + 32] meet [lo, hi]; false when none do.
    static bool tile_range(double lo, double hi, int pixels, int tiles, int& t0, int& t1) {
        if (!(hi >= 0.0) || !(lo <= double(pixels))) return false;
        t0 = lo <= 0.0 ? 0 : std::min(tiles - 1, int(std::floor(lo / kTileSize)));
        t1 = hi >= double(pixels) ? tiles - 1 : std::min(tiles - 1, int(std::floor(hi / kTileSize)));
        return true;
    }

    Scratch make_scratch() const {
        Scratch s;
        s.column_pass.assign(size_t(tiles_x_), 0);
        s.row_pass.assign(size_t(tiles_y_), 0);
        s.stack.reserve(kTreeFanout * (levels_.size() + 1));
        return s;
    }

    // First pass: every photon's pair count. The pairs themselves are kept too, per chunk of photons, as long as
    // all of them fit under the cap (they do at a typical radius): then the second pass is not needed. Once
    // they do not (a photon's pairs would take the kept total past the cap), every chunk drops what it kept.
    // The chunks are fixed ranges of kPhotonsPerChunk photons, so what is kept does not depend on threads.
    void count_pairs() {
        const size_t n = positions_.size();
        const size_t chunks = (n + kPhotonsPerChunk - 1) / kPhotonsPerChunk;
        counts_.assign(n, 0);
        chunk_pairs_.assign(chunks, std::vector<uint32_t>());
        meter_.add(bytes_of(counts_) + bytes_of(chunk_pairs_));
        std::atomic<uint64_t> done{0}, kept{0}, tests{0};
        std::atomic<bool> keep{true};
        tbb::parallel_for(Range(0, chunks, 1), [&](const Range& range) {
            Scratch scratch = make_scratch();
            uint64_t local_tests = 0;
            for (size_t c = range.begin(); c != range.end(); ++c) {
                control_.check();
                std::vector<uint32_t> pairs;
                const size_t begin = c * kPhotonsPerChunk, end = std::min(n, begin + kPhotonsPerChunk);
                for (size_t j = begin; j != end; ++j) {
                    const bool keeping = keep.load(std::memory_order_relaxed);
                    uint32_t count = 0;
                    const int64_t before = bytes_of(pairs);
                    local_tests += bin_photon(uint32_t(j), scratch, [&](uint32_t bin) {
                        ++count;
                        if (keeping) pairs.push_back(bin);
                    });
                    counts_[j] = count;
                    const uint64_t cap = params_.max_pairs_in_memory;
                    if (keeping && kept.fetch_add(count, std::memory_order_relaxed) + count > cap)
                        keep.store(false, std::memory_order_relaxed);
                    if (keeping && !keep.load(std::memory_order_relaxed)) pairs = std::vector<uint32_t>();
                    if (bytes_of(pairs) != before) meter_.add(bytes_of(pairs) - before);
                }
                if (keep.load(std::memory_order_relaxed)) {
                    const int64_t before = bytes_of(pairs);
                    pairs.shrink_to_fit();  // 4 bytes a pair while kept
                    meter_.add(bytes_of(pairs) - before);
                    chunk_pairs_[c] = std::move(pairs);
                }
                report_progress(0.1 * double(done += end - begin) / double(n));
            }
            tests += local_tests;
        });
        for (const uint32_t c : counts_) total_pairs_ += c;
        pairs_kept_ = keep.load();
        if (pairs_kept_) {
            tile_tests_ += tests.load();
        } else {  // binned again, batch by batch
            for (std::vector<uint32_t>& pairs : chunk_pairs_) {
                meter_.add(-bytes_of(pairs));
                pairs = std::vector<uint32_t>();
            }
        }
    }

    // Counting is the first tenth of the splat, shading the pairs the rest (pairs are what shading costs).
    void report_progress(double fraction) const {
        control_.advance(uint64_t(std::clamp(fraction, 0.0, 1.0) * 1e6), 1000000);
    }

    // The per-bin photon lists of photons [begin, end): a stable counting sort of their pairs by bin, in photon
    // order, so every list comes out ascending. The pairs are those count_pairs kept (one batch) or, batch by
    // batch, those of a second binning pass.
    void fill_lists(size_t begin, size_t end) {
        list_begin_.assign(bin_count_ + 1, 0);
        if (pairs_kept_) {
            uint64_t pairs = 0;
            for (const std::vector<uint32_t>& chunk : chunk_pairs_) {
                for (const uint32_t bin : chunk) ++list_begin_[bin + 1];
                pairs += chunk.size();
            }
            list_.resize(pairs);
            for (size_t t = 0; t < bin_count_; ++t) list_begin_[t + 1] += list_begin_[t];
            std::vector<uint64_t> cursor(list_begin_.begin(), list_begin_.end() - 1);
            for (size_t c = 0; c < chunk_pairs_.size(); ++c) {
                const uint32_t* bin = chunk_pairs_[c].data();
                const size_t chunk_end = std::min(end, (c + 1) * kPhotonsPerChunk);
                for (size_t j = c * kPhotonsPerChunk; j != chunk_end; ++j)
                    for (uint32_t u = 0; u != counts_[j]; ++u) list_[cursor[*bin++]++] = uint32_t(j);
                meter_.add(-bytes_of(chunk_pairs_[c]));
                chunk_pairs_[c] = std::vector<uint32_t>();
            }
            return;
        }
        const size_t n = end - begin;
        photon_offsets_.resize(n + 1);
        photon_offsets_[0] = 0;
        for (size_t j = begin; j != end; ++j) photon_offsets_[j - begin + 1] = photon_offsets_[j - begin] + counts_[j];
        const uint64_t pairs = photon_offsets_[n];
        pair_tiles_.resize(pairs);
        list_.resize(pairs);
        bin_batch(begin, end);
        control_.check();
        for (uint64_t k = 0; k < pairs; ++k) ++list_begin_[pair_tiles_[k] + 1];
        for (size_t t = 0; t < bin_count_; ++t) list_begin_[t + 1] += list_begin_[t];
        std::vector<uint64_t> cursor(list_begin_.begin(), list_begin_.end() - 1);
        for (size_t j = begin; j != end; ++j)
            for (uint64_t k = photon_offsets_[j - begin]; k != photon_offsets_[j - begin + 1]; ++k)
                list_[cursor[pair_tiles_[k]]++] = uint32_t(j);
    }

    // Second binning pass for photons [begin, end): their pairs, at the offsets their counts give.
    void bin_batch(size_t begin, size_t end) {
        std::atomic<uint64_t> tests{0};
        tbb::parallel_for(Range(begin, end, kPhotonsPerChunk), [&](const Range& range) {
            control_.check();
            Scratch scratch = make_scratch();
            uint64_t local_tests = 0;
            for (size_t j = range.begin(); j != range.end(); ++j) {
                uint64_t k = photon_offsets_[j - begin];
                const uint64_t k_end = photon_offsets_[j - begin + 1];
                local_tests += bin_photon(uint32_t(j), scratch, [&](uint32_t tile) {
                    if (k == k_end) throw std::logic_error("tiled splat: binning is not deterministic");
                    pair_tiles_[k++] = tile;
                });
                if (k != k_end) throw std::logic_error("tiled splat: binning is not deterministic");
            }
            tests += local_tests;
        });
        tile_tests_ += tests.load();
    }

    // ---- 3. shading ----------------------------------------------------------------------------------------
    // Each bin shades its samples from its list, in list (= photon) order. The list is taken in segments of
    // kSegment photons, copied together (as the paper copies a tile's photons to shared memory; this also
    // bounds the copy whatever the list's length): positions as three arrays padded with +inf to a multiple of
    // kBlock, so that the distance test, which rejects nearly every pair, runs on kBlock photons at a time in
    // vector registers; the photons it keeps (with room to spare: r²·(1 + 1e-5)) get the full per-sample test
    // of splat.h, which decides. A sample's running sum goes from segment to segment in order, so it still adds
    // its photons one by one in ascending order into one glm::dvec3.
    static constexpr size_t kBlock = 16;  // (the any-test below reads it as two 64-bit words)
    static constexpr size_t kSegment = 4096;

    void shade(bool last) {
        const bool carried = !sums_.empty();
        tbb::parallel_for(Range(0, bin_count_, 1), [&](const Range& range) {
            std::vector<float> xs, ys, zs;     // the segment's photon positions, for the distance test
            std::vector<glm::vec3> positions;  // and again with their records, for the full test
            std::vector<Photon> records;
            std::vector<glm::dvec3> running;   // per sample of the bin, between segments
            uint64_t tests = 0, contributing = 0, shaded_pairs = 0;
            for (size_t t = range.begin(); t != range.end(); ++t) {
                const uint32_t* list = list_.data() + list_begin_[t];
                const size_t list_size = size_t(list_begin_[t + 1] - list_begin_[t]);
                if (list_size == 0 && !last) continue;
                const uint32_t sample_begin = bin_samples_begin_[t], sample_end = bin_samples_begin_[t + 1];
                running.resize(sample_end - sample_begin);
                size_t segment_begin = 0;
                do {
                    control_.check();
                    const size_t segment_end = std::min(list_size, segment_begin + kSegment);
                    const size_t size = segment_end - segment_begin;
                    const size_t padded = (size + kBlock - 1) / kBlock * kBlock;
                    xs.assign(padded, std::numeric_limits<float>::infinity());
                    ys.assign(padded, std::numeric_limits<float>::infinity());
                    zs.assign(padded, std::numeric_limits<float>::infinity());
                    positions.resize(size);
                    records.resize(size);
                    for (size_t m = 0; m != size; ++m) {
                        const uint32_t j = list[segment_begin + m];
                        const glm::vec3& p = positions_[j];
                        xs[m] = p.x, ys[m] = p.y, zs[m] = p.z;
                        positions[m] = p;
                        records[m] = photons_[j];
                    }
                    const bool first = segment_begin == 0, final = segment_end == list_size;
                    for (uint32_t k = sample_begin; k != sample_end; ++k) {
                        if ((k - sample_begin) % kSamplesPerCancelCheck == 0) control_.check();
                        const uint32_t i = bin_samples_[k];
                        const ViewSample& s = views_[i];
                        const float sx = s.position.x, sy = s.position.y, sz = s.position.z;
                        glm::dvec3 reflected_flux =
                            !first ? running[k - sample_begin] : carried ? sums_[i] : glm::dvec3(0.0);
                        for (size_t m0 = 0; m0 < padded; m0 += kBlock) {
                            uint8_t near[kBlock];
                            for (size_t u = 0; u < kBlock; ++u) {
                                const float dx = sx - xs[m0 + u], dy = sy - ys[m0 + u], dz = sz - zs[m0 + u];
                                near[u] = (dx * dx + dy * dy + dz * dz) < prefilter_sq_;
                            }
                            uint64_t any[kBlock / 8];
                            std::memcpy(any, near, sizeof(near));
                            if ((any[0] | any[1]) == 0) continue;
                            for (size_t u = 0; u < kBlock; ++u) {
                                if (!near[u]) continue;
                                const glm::vec3& p = positions[m0 + u];
                                const Photon& photon = records[m0 + u];
                                if (!photon_reaches_sample(s, p, photon, params_)) continue;
                                reflected_flux += photon_reflected_flux(s, lobes_, p, photon, params_);
                                ++contributing;
                            }
                        }
                        if (!final)
                            running[k - sample_begin] = reflected_flux;
                        else if (last)
                            radiance_[i] = finish_sample(s, reflected_flux, params_);
                        else
                            sums_[i] = reflected_flux;
                    }
                    segment_begin = segment_end;
                } while (segment_begin < list_size);
                tests += uint64_t(list_size) * (sample_end - sample_begin);
                shaded_pairs += list_size;
            }
            sample_tests_ += tests;
            contributing_ += contributing;
            if (shaded_pairs > 0) {
                const double shaded = double(pairs_shaded_ += shaded_pairs);
                report_progress(0.1 + 0.9 * shaded / double(std::max<uint64_t>(total_pairs_, 1)));
            }
        });
    }

    const ViewFrame frame_;
    const int width_, height_, tiles_x_, tiles_y_;
    const glm::vec3 eye_;      // camera position relative to the samples' origin
    const glm::vec3 forward_;  // view depth axis
    float reject_box_sq_ = 0.0f, prefilter_sq_ = 0.0f;
    double max_plane_offset_ = 0.0;

    std::vector<Plane> columns_, rows_;           // tile boundary planes: tiles_x_ + 1 and tiles_y_ + 1
    std::vector<TileBounds> tiles_;
    std::vector<std::vector<Box>> levels_;        // tree over the outside groups: levels_[0][g] is group g's box
    size_t group_count_ = 0, bin_count_ = 0;      // bins: the tiles, then the outside groups
    std::vector<uint32_t> bin_samples_begin_;     // CSR: bin b's samples are bin_samples_[begin[b], begin[b+1])
    std::vector<uint32_t> bin_samples_;

    std::vector<uint32_t> counts_;          // pairs per photon
    std::vector<std::vector<uint32_t>> chunk_pairs_;  // count_pairs' pairs per chunk, when all fit under the cap
    bool pairs_kept_ = false;
    std::vector<uint64_t> photon_offsets_;  // the batch's pairs per photon, as offsets into pair_tiles_
    std::vector<uint32_t> pair_tiles_;      // the tile of every pair of the batch, photons ascending
    std::vector<uint64_t> list_begin_;      // CSR offsets of the per-tile lists
    std::vector<uint32_t> list_;            // the batch's per-tile photon lists
    std::vector<glm::dvec3> sums_;          // per sample: Σ f_r·Φ so far; empty while there is one batch
    std::vector<glm::vec3> radiance_;

    ByteMeter meter_;
    uint64_t total_pairs_ = 0, batches_ = 0;
    std::atomic<uint64_t> pairs_shaded_{0};
    std::atomic<uint64_t> tile_tests_{0}, sample_tests_{0}, contributing_{0};
};

}  // namespace

glm::dvec4 tiled_sphere_screen_bounds(const Camera& camera, const glm::vec3& center, float radius) {
    return sphere_screen_rect(view_frame(camera), glm::dvec3(center), double(radius));
}

std::vector<glm::vec3> splat_tiled(const ViewSamples& samples, const Camera& camera, const PhotonMap& photons,
                                   const SplatParams& params, const RenderControl& control, Stats& stats) {
    validate(params, photons);
    if (samples.width != camera.width() || samples.height != camera.height())
        throw InvalidInput("camera", std::to_string(camera.width()) + "×" + std::to_string(camera.height()) +
                                         " does not match the view samples' " + std::to_string(samples.width) +
                                         "×" + std::to_string(samples.height));
    if (photons.photons.size() >= std::numeric_limits<uint32_t>::max())
        throw InvalidInput("photons", "too many photons for 32-bit photon indices");
    control.check();
    for (const char* name : {"photon_tile_tests", "photon_sample_tests", "contributing_pairs", "tile_photon_pairs",
                             "splat_batches"})
        stats.counters[name] += 0.0;  // present even when there is nothing to splat
    const std::vector<ViewSample>& views = samples.samples;
    if (views.empty() || photons.photons.empty()) {
        stats.bytes["tile_bounds"] = 0.0;
        stats.bytes["tile_photon_lists"] = 0.0;
        return std::vector<glm::vec3>(views.size(), glm::vec3(0.0f));  // (emitted may be 0: nothing to finish)
    }
    return TiledSplat(samples, camera, photons, params, control, stats).run();
}


namespace {

class TiledSplatter final : public Splatter {
public:
    SplatMemory predict_memory(const SplatFrame& frame, size_t photons, const SplatParams&) const override {
        const Camera& camera = frame.camera;
        const double s = double(frame.samples.samples.size()), p = double(photons);
        const double tiles = std::ceil(camera.width() / 32.0) * std::ceil(camera.height() / 32.0);
        SplatMemory m;
        m.fixed["tile_bounds"] = tiles * (12.0 + 2.0 * 24.0) + (camera.width() + camera.height()) * 16.0 / 32.0 + 64.0;
        m.fixed["tile_samples"] = (s + tiles + s / 32.0 + 2.0) * 4.0;
        m.fixed["photon_positions"] = photon_position_bytes(photons);
        m.fixed["splat_sample_sums"] = sample_sum_bytes(frame.samples.samples.size());
        m.pair_key = "tile_photon_lists";
        m.pair_fixed = p * 8.0 + tiles * 8.0 + double(std::max(frame.threads, 1)) * 64.0;  // counts, offsets, chunks
        m.per_pair = kPairBytesAtPeak;
        return m;
    }
    SplatEstimate splat(const SplatFrame& frame, const PhotonMap& photons, const SplatParams& params,
                        const RenderControl& control, Stats& stats) const override {
        return {splat_tiled(frame.samples, frame.camera, photons, params, control, stats)};
    }
};

}  // namespace

std::unique_ptr<Splatter> make_tiled_splatter(const RenderSettings&) { return std::make_unique<TiledSplatter>(); }

}  // namespace ps
