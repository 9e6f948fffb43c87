// The tape tree: an octree over a root box around the scene, built once per frame before
// the tiles. A cell's 8 children are evaluated as 8 interval lanes with the cell's tape;
// each child gets the tape simplified for its box (runtime/eval/interval.hpp: the same floats as
// the full program at every point of the box) and its interval [ivlo, ivhi]. Leaves keep
// their tapes (in `tapes`). Leaf 0 stands for everything outside the root box:
// the full program, never skipped.
//
// Rays locate the leaf of each point (a lane caches its leaf's box), evaluate that leaf's
// tape, and when the leaf's interval proves it empty (no surface: for a 1-Lipschitz bound,
// d >= ivlo > 0 everywhere in it) jump to where they leave the box, plus ivlo; or, outside
// solids, to where they leave the biggest box around it whose leaves are all empty
// (Leaf::up), plus that box's least bound (NodeBox::elo).
// The build (split policy, budgets) is in tape_tree.cpp; the lookups are here, inline,
// because every ray step makes one.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "compiler/bytecode/program.hpp"

namespace sdfc::cpu {

constexpr size_t kTreeMinProgram = 128;  // shorter programs get no tree (lookups would cost more)

// A raw field's box whose values are proven not negative holds no sign change (at most
// zeros: a sheet of zero thickness, which the marches do not take for a surface): its lower
// bound [lo, hi] is raised from 0 to kSheet, so that it counts as empty (tree cells and
// Worker::segment_bounds alike).
constexpr float kSheet = std::numeric_limits<float>::min();
inline float raw_floor(float lo, float hi) { return lo >= 0.0f && lo < kSheet && hi > 0.0f ? kSheet : lo; }

struct TapeTree {
    static constexpr uint32_t kLeafBit = 0x80000000u;
    struct Node {                 // what a descent reads: 16 bytes
        float c[3] = {0, 0, 0};   // split point: children with x >= c[0] have bit 0 set, ...
        uint32_t child = kLeafBit;  // first of 8 children, or kLeafBit | leaf index
    };
    struct NodeBox {              // what a climb reads
        float lo[3] = {0, 0, 0};
        uint32_t parent = 0;
        float hi[3] = {0, 0, 0};
        // The least of its leaves' ivlo when every leaf under it is proven empty (> 0: the
        // field is at least that all over the box), else -inf.
        float elo = -INFINITY;
        bool empty() const { return elo > 0.0f; }
        bool holds(float x, float y, float z) const {
            return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
        }
    };
    struct alignas(64) Leaf {  // one cache line
        float lo[3], hi[3];  // the box (leaf 0: empty box, so that lanes always re-locate)
        float ivlo, ivhi;    // the distance over the box
        const Instr* code;   // its tape (in `tapes`), len instructions, output register out
        uint32_t len;
        uint16_t out;
        uint32_t node;       // its node (leaf 0: the root)
        // The biggest node around an empty leaf all of whose leaves are empty (a ray outside
        // solids may jump through its whole box); else the leaf's own node.
        uint32_t up;
        const Guard* guards = nullptr;  // leaf 0: the program's (the VM skips far regions)
        // The tape for an evaluator sized to the tree's max_regs.
        TapeView view() const { return TapeView{code, len, &out, 1, 0, TapeView::kUncounted, guards}; }
        bool holds(float x, float y, float z) const {
            return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
        }
    };
    static_assert(sizeof(Leaf) == 64);
    glm::vec3 lo{0}, hi{0};
    std::vector<Node> nodes;
    std::vector<NodeBox> boxes_;
    // Ropes: row l (kRopeRow entries) holds, for each face of leaf l's box (-x, +x, -y, +y,
    // -z, +z), the smallest node at least as big as the leaf on the other side of that face
    // (0, the root, past the root's faces), then the leaf's own node. A point that left a
    // leaf's box starts its lookup there instead of climbing from the leaf: a jump's landing
    // point is nearly always in that neighbour.
    static constexpr int kRopeRow = 8;
    std::vector<uint32_t> ropes;
    std::vector<Leaf> leaves;
    std::vector<std::vector<Instr>> tapes;  // [0]: the full program
    std::vector<Guard> guards;  // the full program's (leaf 0's): the tree outlives the program it was built from (tree_cache.hpp)
    uint32_t max_regs = 1;
    float time = 0.0f;  // the tapes' (a tree is built for one time: tree_cache.hpp)
    uint64_t boxes = 0;
    bool active = false;

    // Leaf 0 only: the full program everywhere.
    void init_full(const Program& p) {
        tapes.assign(1, p.code);
        guards = p.guards;
        constexpr float inf = INFINITY;
        leaves.assign(1, Leaf{{inf, inf, inf}, {-inf, -inf, -inf}, -inf, inf, tapes[0].data(), static_cast<uint32_t>(tapes[0].size()),
                              p.outputs.empty() ? uint16_t(0) : p.outputs[0], 0, 0, guards.empty() ? nullptr : guards.data()});
        max_regs = std::max<uint32_t>(p.num_regs, 1);
        nodes.clear();
        boxes_.clear();
        ropes.clear();
        active = false;
    }

    uint32_t descend(uint32_t n, float x, float y, float z) const {
        for (;;) {
            const Node& N = nodes[n];
            if (N.child & kLeafBit) return N.child & ~kLeafBit;
            n = N.child + uint32_t(x >= N.c[0]) + 2u * uint32_t(y >= N.c[1]) + 4u * uint32_t(z >= N.c[2]);
        }
    }
    uint32_t locate(float x, float y, float z) const {
        if (!active || !boxes_[0].holds(x, y, z)) return 0;
        return descend(0, x, y, z);
    }
    // The face of box [lo, hi] that point p is beyond (the last one tested wins: any will
    // do), or 6 when p is in the box.
    static int face_beyond(const float lo[3], const float hi[3], float x, float y, float z) {
        int f = 6;
        f = z > hi[2] ? 5 : f;
        f = z < lo[2] ? 4 : f;
        f = y > hi[1] ? 3 : f;
        f = y < lo[1] ? 2 : f;
        f = x > hi[0] ? 1 : f;
        f = x < lo[0] ? 0 : f;
        return f;
    }
    // Where the lookup of a point that left leaf `near` (across face f) starts.
    uint32_t rope(uint32_t near, int f) const { return ropes[size_t(near) * kRopeRow + size_t(f)]; }
    // The leaf of the point, from node n: up to the first node that holds it, then down.
    uint32_t find_from(uint32_t n, float x, float y, float z) const {
        while (n != 0 && !boxes_[n].holds(x, y, z)) n = boxes_[n].parent;
        if (n == 0 && !boxes_[0].holds(x, y, z)) return 0;
        return descend(n, x, y, z);
    }
    // Whether every leaf that meets the box [blo, bhi] is proven empty (ivlo > 0: the field
    // is positive all over it), the box inside the root's. False too when that takes more
    // than kEmptyVisits nodes (a box over much fine detail: not worth proving).
    static constexpr int kEmptyVisits = 256;
    bool all_empty(const glm::vec3& blo, const glm::vec3& bhi) const;
    // The same, starting from leaf `near` (itself, or through its rope).
    uint32_t locate_from(uint32_t near, float x, float y, float z) const {
        if (!active) return 0;
        if (leaves[near].holds(x, y, z)) return near;
        const Leaf& L = leaves[near];
        return find_from(rope(near, face_beyond(L.lo, L.hi, x, y, z)), x, y, z);
    }
};

// Builds the tree over [lo, hi] for output 0 of `p` (call inside the render's task arena;
// see tape_tree.cpp for the order and the budgets). `lipschitz`: `p` is a 1-Lipschitz
// distance bound (cells' intervals may be tightened with centre values). `samples`: the
// image's primary rays, which scale the build's work and node budgets. `thin_layer`: the
// root was centred under a thin layer of surfaces (frame.hpp tree_root), which takes a
// smaller node budget.
void build_tree(TapeTree& T, const Program& p, glm::vec3 lo, glm::vec3 hi, float time, bool lipschitz, size_t samples,
                bool thin_layer = false);

}  // namespace sdfc::cpu
