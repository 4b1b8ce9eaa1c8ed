// Stage 3 of the pipeline: the view-sample cluster hierarchy (Sintorn et al. 2014, as used by Moreau et al.
// 2016). Leaves are the distinct cluster keys: an 8×8 pixel tile and a logarithmic depth slice, interleaved as
// a Morton code. Parents are key prefixes (3 bits a level, so up to 8 children); single-child chains are
// collapsed. Samples reached through mirrors or glass are keyed by their real 3D position in a subtree of
// their own, because their pixel says nothing about where they are.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace ps {

struct ViewSamples;
class Camera;

struct ClusterNode {
    glm::vec3 box_min, box_max;   // bounds of the node's samples, relative to ViewSamples::origin
    uint32_t first_child;         // children are nodes[first_child, first_child + child_count)
    uint32_t child_count;         // 0 for a leaf
    uint32_t sample_begin;        // the node's samples are sample_order[sample_begin, sample_end)
    uint32_t sample_end;
};

// Parameters of the cluster key, taken from the camera.
struct ClusterKeyParams {
    int width = 0, height = 0;
    bool orthographic = false;
    float near_clip = 0.1f;           // perspective: depth of slice 0
    float vertical_half_extent = 1.0f; // perspective: tan(fovY/2); orthographic: half view height
    static ClusterKeyParams from_camera(const Camera& camera);
};

struct ClusterHierarchy {
    static constexpr int kTileSize = 8;

    std::vector<ClusterNode> nodes;       // root is nodes[root]
    uint32_t root = 0;
    std::vector<uint32_t> sample_order;   // indices into ViewSamples::samples, grouped by leaf
    std::vector<uint32_t> leaves;         // node indices of the leaves, in key order
    int depth = 0;                        // levels from root to the deepest leaf

    bool empty() const { return nodes.empty(); }
    size_t bytes() const;
};

// Depth slice of the cluster key (Olsson et al. 2012): k = floor(ln(z/near) / ln(1 + 2 tan(fovY/2) / tilesY)),
// clamped to [0, 2^21 − 1]; orthographic cameras use linear slices one tile high.
uint32_t depth_slice(float depth, const ClusterKeyParams& params);

ClusterHierarchy build_cluster_hierarchy(const ViewSamples& samples, const ClusterKeyParams& params);

}  // namespace ps
