#include "compiler/ir/ir.hpp"

#include <bit>
#include <cmath>

#include <fmt/format.h>

namespace sdfc {

Graph::Graph() {
    nodes_.reserve(1024);
    table_.assign(2048, kNoNode);
}

uint64_t Graph::hash(const Node& n) {
    auto mix = [](uint64_t h) {  // murmur3's finaliser
        h ^= h >> 33; h *= 0xff51afd7ed558ccdull; h ^= h >> 33; h *= 0xc4ceb9fe1a85ec53ull; h ^= h >> 33;
        return h;
    };
    uint64_t ab = uint64_t(n.a) | (uint64_t(n.b) << 32);
    uint64_t ck = uint64_t(n.c) | (uint64_t(std::bit_cast<uint32_t>(n.k)) << 32);
    return mix(mix(ab ^ uint64_t(n.op)) + ck);
}

void Graph::grow_table() {
    std::vector<NodeId> t(table_.size() * 2, kNoNode);
    const size_t mask = t.size() - 1;
    for (NodeId id = 0; id < nodes_.size(); ++id) {
        size_t i = hash(nodes_[id]) & mask;
        while (t[i] != kNoNode) i = (i + 1) & mask;
        t[i] = id;
    }
    table_.swap(t);
}

NodeId Graph::intern(const Node& n) {
    const size_t mask = table_.size() - 1;
    const uint32_t kbits = std::bit_cast<uint32_t>(n.k);
    size_t i = hash(n) & mask;
    for (;; i = (i + 1) & mask) {
        NodeId id = table_[i];
        if (id == kNoNode) break;
        const Node& m = nodes_[id];
        if (m.op == n.op && m.a == n.a && m.b == n.b && m.c == n.c && std::bit_cast<uint32_t>(m.k) == kbits) return id;
    }
    if (nodes_.size() >= node_limit_)
        throw CompileError(cur_loc_, fmt::format("the program grew past {} operations (raise it with --max-ops)", node_limit_));
    NodeId id = static_cast<NodeId>(nodes_.size());
    nodes_.push_back(n);
    uint8_t f = 0;
    if (n.op == Op::Time) f |= kTime;
    if (n.op == Op::VarX || n.op == Op::VarY || n.op == Op::VarZ) f |= kPoint;
    for (NodeId arg : {n.a, n.b, n.c})
        if (arg != kNoNode) f |= flags_[arg];
    flags_.push_back(f);
    locs_.push_back(cur_loc_);
    table_[i] = id;
    if (nodes_.size() * 2 > table_.size()) grow_table();  // load factor <= 1/2
    return id;
}

NodeId Graph::constant(float v) {
    if (v == 0.0f) v = 0.0f;  // one zero: -0 and +0 share a node
    return intern(Node{Op::Const, kNoNode, kNoNode, kNoNode, v});
}

NodeId Graph::input(Op op) { return intern(Node{op}); }

NodeId Graph::unary(Op op, NodeId a) {
    if (is_const(a)) return constant(eval_op(op, const_value(a), 0, 0, 0));
    const Node& na = nodes_[a];
    switch (op) {
        case Op::Neg:
            if (na.op == Op::Neg) return na.a;
            break;
        case Op::Abs:
            if (na.op == Op::Abs || na.op == Op::Square || na.op == Op::Sqrt || na.op == Op::Length2 ||
                na.op == Op::Length3)
                return a;
            if (na.op == Op::Neg) return unary(Op::Abs, na.a);
            break;
        case Op::Copy:
            return a;
        default:
            break;
    }
    return intern(Node{op, a});
}

NodeId Graph::binary(Op op, NodeId a, NodeId b) {
    bool ca = is_const(a), cb = is_const(b);
    if (ca && cb) return constant(eval_op(op, const_value(a), const_value(b), 0, 0));
    float va = ca ? const_value(a) : 0.0f, vb = cb ? const_value(b) : 0.0f;
    switch (op) {
        case Op::Add:
            if (ca && va == 0.0f) return b;
            if (cb && vb == 0.0f) return a;
            if (nodes_[b].op == Op::Neg) return binary(Op::Sub, a, nodes_[b].a);
            break;
        case Op::Sub:
            if (cb && vb == 0.0f) return a;
            if (ca && va == 0.0f) return unary(Op::Neg, b);
            if (cb) return binary(Op::Add, a, constant(-vb));
            if (a == b) return constant(0.0f);
            break;
        case Op::Mul:
            if (ca && va == 1.0f) return b;
            if (cb && vb == 1.0f) return a;
            if (ca && va == -1.0f) return unary(Op::Neg, b);
            if (cb && vb == -1.0f) return unary(Op::Neg, a);
            if ((ca && va == 0.0f) || (cb && vb == 0.0f)) return constant(0.0f);
            if (a == b) return unary(Op::Square, a);
            break;
        case Op::Div:
            if (cb && vb == 1.0f) return a;
            break;
        case Op::Min:
        case Op::Max:
            if (a == b) return a;
            break;
        case Op::Pow:
            if (cb && vb == 1.0f) return a;
            if (cb && vb == 2.0f) return unary(Op::Square, a);
            if (cb && vb == 0.5f) return unary(Op::Sqrt, a);
            break;
        default:
            break;
    }
    // Canonical operand order for commutative ops improves sharing.
    if ((op == Op::Add || op == Op::Mul || op == Op::Min || op == Op::Max || op == Op::Eq || op == Op::Ne) && a > b)
        std::swap(a, b);
    return intern(Node{op, a, b});
}

NodeId Graph::ternary(Op op, NodeId a, NodeId b, NodeId c) {
    if (is_const(a) && is_const(b) && is_const(c))
        return constant(eval_op(op, const_value(a), const_value(b), const_value(c), 0));
    if (op == Op::Select) {
        if (is_const(a)) return const_value(a) != 0.0f ? b : c;
        if (b == c) return b;
    }
    if (op == Op::Mix) {
        if (b == c) return b;
        if (is_const(a) && const_value(a) == 0.0f) return b;
        if (is_const(a) && const_value(a) == 1.0f) return c;
    }
    return intern(Node{op, a, b, c});
}

NodeId Graph::with_imm(Op op, NodeId a, NodeId b, float k) { return intern(Node{op, a, b, kNoNode, k}); }

std::vector<uint8_t> reachable(const Graph& g, const std::vector<NodeId>& roots) {
    std::vector<uint8_t> live(g.size(), 0);
    for (NodeId r : roots) live[r] = 1;
    for (size_t i = g.size(); i-- > 0;) {  // arguments come before their users
        if (!live[i]) continue;
        const Node& n = g.node(static_cast<NodeId>(i));
        for (NodeId arg : {n.a, n.b, n.c})
            if (arg != kNoNode) live[arg] = 1;
    }
    return live;
}

std::string dump_ir(const Graph& g, const std::vector<NodeId>& roots, const std::vector<std::string>& root_names) {
    const std::vector<uint8_t> live = reachable(g, roots);
    std::string out;
    for (size_t i = 0; i < g.size(); ++i) {
        if (!live[i]) continue;
        const Node& n = g.node(static_cast<NodeId>(i));
        const OpInfo& info = op_info(n.op);
        std::string line = fmt::format("%{} = {}", i, info.mnemonic);
        for (NodeId arg : {n.a, n.b, n.c})
            if (arg != kNoNode) line += fmt::format(" %{}", arg);
        if (info.has_imm) line += fmt::format(" {}", n.k);
        Loc l = g.node_loc(static_cast<NodeId>(i));
        if (l.known()) line = fmt::format("{:<40} ; line {}", line, l.line);
        out += line + "\n";
    }
    for (size_t r = 0; r < roots.size(); ++r)
        out += fmt::format("{} = %{}\n", r < root_names.size() ? root_names[r] : fmt::format("out{}", r), roots[r]);
    return out;
}

}  // namespace sdfc
