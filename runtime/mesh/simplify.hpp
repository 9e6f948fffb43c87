// Fewer triangles for the same surface: edge collapses in the order of their quadric error
// (Garland and Heckbert's, from qef.hpp), each kept only where the mesh stays closed,
// 2-manifold and unfolded, and within the tolerance of the field it was made of
// (simplify.cpp has the rules).
#pragma once
#include <cstddef>
#include <functional>

#include <glm/glm.hpp>

#include "runtime/eval/gradient.hpp"
#include "runtime/mesh/mesh.hpp"

namespace sdfc::mesh {

// The meshed field's value and gradient at n points; called from one thread with large
// batches (it may run them in parallel).
using FieldGradient = std::function<void(const glm::vec3* p, size_t n, Dual* out)>;

struct SimplifyStats {
    size_t triangles_before = 0, triangles_after = 0;
    size_t collapses = 0, refused_by_field = 0;
    int rounds = 0;
};

// Simplifies a closed, oriented, 2-manifold mesh in place (its colours, if any, are
// dropped: they are to be made again for the vertices that stay). Every collapse keeps:
//  - the topology: the link condition, no vertex left with fewer than 3 triangles;
//  - the shape: the new vertex, the centroids of its new triangles and the two vertices
//    it replaces within `tolerance` of the surface (the field's |f| / |grad f|, and the
//    distance to the new triangles); no triangle turned by more than about 80 degrees, or
//    made a sliver.
// A surface thinner than the tolerance may still touch itself: the tolerance is a
// distance the user accepts the mesh to be off by.
// `progress` (if set) is called between rounds with the fraction of the work done.
void simplify_mesh(Mesh& m, float tolerance, const FieldGradient& field, SimplifyStats* stats = nullptr,
                   const std::function<void(double)>& progress = {});

}  // namespace sdfc::mesh
