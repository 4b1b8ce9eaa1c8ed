// Random Per Island: see mesh_islands.h. Written from Cycles 3.4's definitions (util/disjoint_set.h,
// blender/mesh.cpp), not copied.
#include "photonsplat/mesh_islands.h"

#include <string>
#include <utility>

#include "nodes/noise.h"
#include "photonsplat/errors.h"

namespace ps {

namespace {

// Union by rank; find compresses the path it walks. Ties in rank keep the first argument's root.
class DisjointSet {
public:
    explicit DisjointSet(size_t n) : parent_(n), rank_(n, 0) {
        for (size_t i = 0; i < n; ++i) parent_[i] = static_cast<uint32_t>(i);
    }

    uint32_t find(uint32_t x) {
        uint32_t root = x;
        while (parent_[root] != root) root = parent_[root];
        while (parent_[x] != root) {
            const uint32_t next = parent_[x];
            parent_[x] = root;
            x = next;
        }
        return root;
    }

    void join(uint32_t x, uint32_t y) {
        uint32_t rx = find(x), ry = find(y);
        if (rx == ry) return;
        if (rank_[rx] < rank_[ry]) std::swap(rx, ry);
        parent_[ry] = rx;
        if (rank_[rx] == rank_[ry]) ++rank_[rx];
    }

private:
    std::vector<uint32_t> parent_;
    std::vector<uint32_t> rank_;
};

}  // namespace

std::vector<uint32_t> island_roots(size_t num_vertices, const int32_t* edges, size_t num_edges) {
    DisjointSet sets(num_vertices);
    for (size_t e = 0; e < num_edges; ++e) {
        const int32_t a = edges[2 * e], b = edges[2 * e + 1];
        if (a < 0 || b < 0 || static_cast<size_t>(a) >= num_vertices || static_cast<size_t>(b) >= num_vertices)
            throw InvalidInput("edges", "edge " + std::to_string(e) + " names a vertex outside [0, " +
                                            std::to_string(num_vertices) + ")");
        sets.join(static_cast<uint32_t>(a), static_cast<uint32_t>(b));
    }
    std::vector<uint32_t> roots(num_vertices);
    for (size_t v = 0; v < num_vertices; ++v) roots[v] = sets.find(static_cast<uint32_t>(v));
    return roots;
}

std::vector<float> random_per_island(size_t num_vertices, const int32_t* edges, size_t num_edges) {
    const std::vector<uint32_t> roots = island_roots(num_vertices, edges, num_edges);
    std::vector<float> values(num_vertices);
    for (size_t v = 0; v < num_vertices; ++v) values[v] = noise::hash_uint_to_float(roots[v]);
    return values;
}

}  // namespace ps
