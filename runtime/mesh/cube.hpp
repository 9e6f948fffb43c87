// A grid cell's corners, edges and faces, and the surface patches of each of the 256 sign
// configurations: which of its sign-changing edges belong to the same piece of surface.
//
// Corner k sits at (k & 1, (k >> 1) & 1, (k >> 2) & 1). Edge e runs along axis e / 4 from
// its lower corner; the other two coordinates are the bits of e % 4 (the lower axis first).
// A patch is one cycle of sign-changing edges, linked across the cell's faces: a face with
// two such edges links them; a face with four (diagonal corners alike, the ambiguous case)
// links each inside corner's two edges, so the inside corners stay apart. The rule looks at
// the face alone, so the two cells sharing a face always agree: one vertex per patch (dual
// marching cubes) then gives a closed, consistently oriented mesh. One case is not a
// manifold: both cells of an ambiguous face having one patch through all four of its edges
// (a tunnel thinner than a cell): their two vertices would be joined twice. The mesher
// flips such a face (links the outside corners' edges instead), which splits both patches
// in two (an oriented patch crosses the face as ab->da ... cd->bc, so the flipped links
// close two cycles), giving one joint per vertex pair.
#pragma once
#include <array>
#include <cstdint>

namespace sdfc::mesh {

// Edge e's two corners (lower first).
constexpr std::array<int, 2> edge_corners(int e) {
    const int axis = e / 4, o = e % 4;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int lo_u = u < v ? u : v, hi_u = u < v ? v : u;  // the lower axis takes bit 0
    const int base = ((o & 1) << lo_u) | (((o >> 1) & 1) << hi_u);
    return {base, base | (1 << axis)};
}

// The edge from corner c0 to corner c1 (which differ in one bit), or -1.
constexpr int edge_between(int c0, int c1) {
    for (int e = 0; e < 12; ++e) {
        const auto c = edge_corners(e);
        if ((c[0] == c0 && c[1] == c1) || (c[0] == c1 && c[1] == c0)) return e;
    }
    return -1;
}

struct Patches {
    uint8_t count = 0;         // patches in the cell (0..4)
    int8_t of_edge[12] = {};   // the patch of each sign-changing edge, -1 for the others
};

// Face f = 2 * axis + side (side 1: the face at coordinate 1); its four edges.
std::array<int, 4> face_edges(int f);

// The patches of configuration `config` (bit k set: corner k inside, f < 0), with the
// ambiguous faces whose bit is set in `flipped` linked the other way.
const Patches& patches(uint8_t config, uint8_t flipped = 0);

}  // namespace sdfc::mesh
