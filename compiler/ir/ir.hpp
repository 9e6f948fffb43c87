// Stage 1 of the compiler: the IR, an SSA graph of scalar operations, hash-consed so equal
// subexpressions are one node (CSE) and folded as they are built (constants, identities).
// The interpreter builds it directly while it evaluates a script symbolically: a number in
// a script is a node here; a script constant is a Const node.
//
//   Tree (Scene: shapes + settings) --lower--> IR Graph --codegen--> Program (register bytecode)
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/ir/opcodes.hpp"
#include "compiler/base/source.hpp"

namespace sdfc {

using NodeId = uint32_t;
inline constexpr NodeId kNoNode = 0xFFFFFFFFu;

struct Node {
    Op op;
    NodeId a = kNoNode, b = kNoNode, c = kNoNode;
    float k = 0.0f;  // immediate (Const value, *_I forms)
};

// A part of the graph that an evaluator may skip: a union's child (compiler/scene/
// shapes_csg.cpp). Where the point (nodes `point`) is outside the box [lo, hi] of the child's
// surface and at least `thr` from it (thr: the union's distance without this child), the
// child cannot be the nearest: `root`, its distance, may be taken as +inf without computing
// what only it (and `extra`, its material channels) needs. Codegen turns regions into guard
// instructions (compiler/bytecode/codegen.cpp); `parent` is the region this one lies in.
struct GuardRegion {
    NodeId root = kNoNode;
    std::vector<NodeId> extra;
    NodeId thr = kNoNode;
    NodeId point[3] = {kNoNode, kNoNode, kNoNode};
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int32_t parent = -1;
};

class Graph {
public:
    Graph();

    // Builders fold constants and simple identities; equal nodes are shared.
    NodeId constant(float v);
    NodeId input(Op op);  // VarX/VarY/VarZ/Time
    NodeId unary(Op op, NodeId a);
    NodeId binary(Op op, NodeId a, NodeId b);
    NodeId ternary(Op op, NodeId a, NodeId b, NodeId c);
    NodeId with_imm(Op op, NodeId a, NodeId b, float k);  // raw *_I node (codegen, .vm import)

    // Convenience
    NodeId add(NodeId a, NodeId b) { return binary(Op::Add, a, b); }
    NodeId sub(NodeId a, NodeId b) { return binary(Op::Sub, a, b); }
    NodeId mul(NodeId a, NodeId b) { return binary(Op::Mul, a, b); }
    NodeId div(NodeId a, NodeId b) { return binary(Op::Div, a, b); }
    NodeId min(NodeId a, NodeId b) { return binary(Op::Min, a, b); }
    NodeId max(NodeId a, NodeId b) { return binary(Op::Max, a, b); }
    NodeId neg(NodeId a) { return unary(Op::Neg, a); }
    NodeId abs(NodeId a) { return unary(Op::Abs, a); }
    NodeId sqrt(NodeId a) { return unary(Op::Sqrt, a); }
    NodeId select(NodeId c, NodeId a, NodeId b) { return ternary(Op::Select, c, a, b); }
    NodeId clamp(NodeId x, NodeId lo, NodeId hi) { return min(max(x, lo), hi); }
    NodeId mix(NodeId a, NodeId b, NodeId t) { return ternary(Op::Mix, t, a, b); }
    NodeId addc(NodeId a, float v) { return add(a, constant(v)); }
    NodeId mulc(NodeId a, float v) { return mul(a, constant(v)); }

    bool is_const(NodeId n) const { return nodes_[n].op == Op::Const; }
    float const_value(NodeId n) const { return nodes_[n].k; }
    bool depends_on_time(NodeId n) const { return flags_[n] & kTime; }
    bool depends_on_point(NodeId n) const { return flags_[n] & kPoint; }

    const Node& node(NodeId n) const { return nodes_[n]; }
    size_t size() const { return nodes_.size(); }

    // Optional source location per node (the script line that made it), for listings and
    // GLSL comments. The current location is attached to every node created after it is set.
    void set_loc(Loc loc) { cur_loc_ = loc; }
    Loc loc() const { return cur_loc_; }
    Loc node_loc(NodeId n) const { return locs_[n]; }

    // Total-node limit (script safety): exceeding it throws CompileError at the current loc.
    void set_node_limit(size_t n) { node_limit_ = n; }

    // Guarded regions, made while lowering; lower_scene clears them (and the context) first,
    // so codegen sees those of the latest lowering (and of what was lowered since).
    int32_t add_guard(const GuardRegion& r) {
        guards_.push_back(r);
        return static_cast<int32_t>(guards_.size() - 1);
    }
    GuardRegion& guard(int32_t i) { return guards_[size_t(i)]; }
    const std::vector<GuardRegion>& guards() const { return guards_; }
    void clear_guards() {
        guards_.clear();
        guard_ctx_ = GuardContext{};
    }
    // What lowering passes down to the unions it meets: the distance a child must beat
    // (kNoNode: none) and the region being lowered (-1: none). Set by unions for their
    // children, cleared below anything that changes distances other than rigidly.
    struct GuardContext {
        NodeId thr = kNoNode;
        int32_t region = -1;
    };
    GuardContext guard_context() const { return guard_ctx_; }
    void set_guard_context(GuardContext c) { guard_ctx_ = c; }

private:
    enum : uint8_t { kTime = 1, kPoint = 2 };
    NodeId intern(const Node& n);
    static uint64_t hash(const Node& n);
    void grow_table();
    std::vector<Node> nodes_;
    std::vector<uint8_t> flags_;
    std::vector<Loc> locs_;
    // Open-addressing hash set of node ids (power-of-two size, linear probing, kNoNode =
    // empty); the key is the node itself, so nothing but the id is stored.
    std::vector<NodeId> table_;
    Loc cur_loc_;
    size_t node_limit_ = 20'000'000;
    std::vector<GuardRegion> guards_;
    GuardContext guard_ctx_;
};

// 1 for each node `roots` read, directly or through others (the roots included), else 0.
std::vector<uint8_t> reachable(const Graph& g, const std::vector<NodeId>& roots);

// Readable listing of the nodes reachable from `roots` (`sdfc compile --emit ir`).
std::string dump_ir(const Graph& g, const std::vector<NodeId>& roots, const std::vector<std::string>& root_names);

}  // namespace sdfc
