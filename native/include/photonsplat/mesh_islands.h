// Random Per Island (the Geometry node's output), computed as Cycles 3.4's Blender sync does
// (intern/cycles/blender/mesh.cpp, attr_create_random_per_island): a disjoint set over the mesh's vertices with
// union by rank and path compression, joined edge by edge in Blender's edge order; each island's value is
// hash_uint_to_float of its root vertex index. The root depends on the order of the joins and on the ranks, so
// this is sequential by nature: the add-on calls it through the module (photonsplat._core.random_per_island)
// rather than emulate it in numpy.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ps {

// The root vertex of each vertex's island after joining `edges` (pairs of vertex indices, in order).
// Throws InvalidInput("edges", ...) for an index outside [0, num_vertices).
std::vector<uint32_t> island_roots(size_t num_vertices, const int32_t* edges, size_t num_edges);

// Cycles' Random Per Island of each vertex: hash_uint_to_float(root of its island).
std::vector<float> random_per_island(size_t num_vertices, const int32_t* edges, size_t num_edges);

}  // namespace ps
