// Stage 2: lowering a shape tree to IR at a symbolic point. Every primitive and operation
// of LANGUAGE.md sections 5-6 is one row of shapes.def (its parameters) and one function
// pair in its family's file, shapes_{primitives,csg,modifiers}.cpp (its formula's source,
// its Lipschitz bound, its bounding box).
#pragma once
#include "compiler/scene/scene.hpp"

namespace sdfc {

struct Lowered {
    NodeId d;        // distance (not yet divided by lip)
    float lip;       // Lipschitz bound of d
    MaterialN m;     // valid when lowered with materials
};

// The distance of `shape` at p, scaled to be 1-Lipschitz (what `s(p)` means in a script).
NodeId lower_distance(Graph& g, const Shape& shape, const Vec3N& p);

// Distance and material channels; `inherited` is the material of the enclosing scope.
Lowered lower_shape(Graph& g, const Shape& shape, const Vec3N& p, const MaterialN* inherited);

// Conservative axis-aligned bounds of the shape's surface; infinite when unknown.
Bounds shape_bounds(const Graph& g, const Shape& shape);

// Where a surface can be, for clipping rays in scenes with a floor: the planes of the
// top-level unions (through material modifiers, and translations and rotations by
// constants) as half-spaces n.p <= w (unit n), and a
// box around everything else (`box` is joined to; it stays empty if there is nothing
// else). False when something else is unbounded or a plane's parameters are not constants.
bool clip_regions(const Graph& g, const Shape& shape, Bounds& box, std::vector<glm::vec4>& half_spaces);

// Rotation matrices (row-major) from angles in degrees, as IR so they may depend on time.
std::array<NodeId, 9> rotation_xyz(Graph& g, NodeId ax, NodeId ay, NodeId az);
std::array<NodeId, 9> rotation_axis_angle(Graph& g, NodeId angle_deg, const Vec3N& axis);

}  // namespace sdfc
