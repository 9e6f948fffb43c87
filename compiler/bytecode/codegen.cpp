// IR Graph -> register Program: instruction selection (immediate forms, MulAddI fusion),
// then linear-scan register allocation in SSA order (the policy of regalloc.hpp).
#include <algorithm>
#include <limits>

#include <fmt/format.h>

#include "compiler/bytecode/program.hpp"
#include "compiler/bytecode/regalloc.hpp"

namespace sdfc {
namespace {

// The immediate form of a binary op whose operand `which` (0 = a, 1 = b) is the constant.
bool imm_form(Op op, int which_const, Op& out, bool& invert) {
    invert = false;
    switch (op) {
        case Op::Add: out = Op::AddI; return true;
        case Op::Mul: out = Op::MulI; return true;
        case Op::Min: out = Op::MinI; return true;
        case Op::Max: out = Op::MaxI; return true;
        case Op::Sub: if (which_const == 0) { out = Op::SubI; return true; } return false;
        case Op::Div:
            if (which_const == 0) { out = Op::DivI; return true; }
            out = Op::MulI; invert = true; return true;  // x / c == x * (1/c) to within an ulp
        case Op::Mod: if (which_const == 1) { out = Op::ModI; return true; } return false;
        case Op::Pow: if (which_const == 1) { out = Op::PowI; return true; } return false;
        default: return false;
    }
}

struct Sel {
    Op op;
    NodeId a = kNoNode, b = kNoNode, c = kNoNode;
    float k = 0.0f;
    bool emit = false;
};

}  // namespace

Program codegen(const Graph& g, const std::vector<NodeId>& roots, const std::vector<std::string>& names) {
    const size_t n = g.size();
    std::vector<uint8_t> live(n, 0);
    for (NodeId r : roots) live[r] = 1;
    for (size_t i = n; i-- > 0;) {
        if (!live[i]) continue;
        const Node& nd = g.node(static_cast<NodeId>(i));
        for (NodeId arg : {nd.a, nd.b, nd.c})
            if (arg != kNoNode) live[arg] = 1;
    }

    // Instruction selection.
    std::vector<Sel> sel(n);
    for (size_t i = 0; i < n; ++i) {
        if (!live[i]) continue;
        const Node& nd = g.node(static_cast<NodeId>(i));
        Sel s{nd.op, nd.a, nd.b, nd.c, nd.k, true};
        if (op_info(nd.op).arity == 2 && !op_info(nd.op).has_imm) {
            bool ca = g.is_const(nd.a), cb = g.is_const(nd.b);
            Op f; bool inv;
            if (cb && imm_form(nd.op, 1, f, inv)) {
                float k = g.const_value(nd.b);
                s = Sel{f, nd.a, kNoNode, kNoNode, inv ? 1.0f / k : k, true};
            } else if (ca && imm_form(nd.op, 0, f, inv)) {
                s = Sel{f, nd.b, kNoNode, kNoNode, g.const_value(nd.a), true};
            }
        }
        sel[i] = s;
    }
    // Use counts over selected instructions, then fuse Add(MulI(x), y) when the MulI has one use.
    auto count_uses = [&](std::vector<uint32_t>& uses) {
        std::fill(uses.begin(), uses.end(), 0);
        for (size_t i = 0; i < n; ++i)
            if (sel[i].emit)
                for (NodeId arg : {sel[i].a, sel[i].b, sel[i].c})
                    if (arg != kNoNode) ++uses[arg];
        for (NodeId r : roots) ++uses[r];
    };
    std::vector<uint32_t> uses(n);
    count_uses(uses);
    for (size_t i = 0; i < n; ++i) {
        Sel& s = sel[i];
        if (!s.emit || s.op != Op::Add) continue;
        for (int side = 0; side < 2; ++side) {
            NodeId m = side == 0 ? s.a : s.b, other = side == 0 ? s.b : s.a;
            if (sel[m].emit && sel[m].op == Op::MulI && uses[m] == 1) {
                s = Sel{Op::MulAddI, sel[m].a, other, kNoNode, sel[m].k, true};
                sel[m].emit = false;
                break;
            }
        }
    }
    count_uses(uses);
    for (size_t i = 0; i < n; ++i)
        if (sel[i].emit && uses[i] == 0) sel[i].emit = false;  // fused away

    // Last use (instruction index in node order); roots live to the end.
    constexpr uint32_t kForever = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> last(n, 0);
    for (size_t i = 0; i < n; ++i)
        if (sel[i].emit)
            for (NodeId arg : {sel[i].a, sel[i].b, sel[i].c})
                if (arg != kNoNode) last[arg] = std::max<uint32_t>(last[arg], static_cast<uint32_t>(i));
    for (NodeId r : roots) last[r] = kForever;

    Program p;
    std::vector<int32_t> reg(n, -1);
    std::vector<uint16_t> free_stack;
    RegPool pool(free_stack, n + 1);  // each node's value is emitted at most once
    auto alloc = [&]() -> uint16_t {
        if (pool.exhausted()) throw CompileError(Loc{}, "the program needs more than 65535 registers");
        return pool.alloc();
    };
    auto emit = [&](NodeId id, const Sel& s) {
        Instr in{s.op};
        in.k = s.k;
        uint16_t* slots[3] = {&in.a, &in.b, &in.c};
        NodeId args[3] = {s.a, s.b, s.c};
        for (int j = 0; j < 3; ++j)
            if (args[j] != kNoNode) *slots[j] = static_cast<uint16_t>(reg[args[j]]);
        // Free operands whose last use is this instruction, before allocating the result,
        // so the result may reuse an operand's register (lane-wise ops are safe in place).
        for (int j = 0; j < 3; ++j) {
            NodeId a = args[j];
            if (a == kNoNode || last[a] != id || reg[a] < 0) continue;
            bool dup = false;
            for (int q = 0; q < j; ++q) dup |= args[q] == a;
            if (!dup) pool.release(static_cast<uint16_t>(reg[a]));
        }
        in.out = alloc();
        reg[id] = in.out;
        p.code.push_back(in);
        p.locs.push_back(g.node_loc(id));
        if (s.op == Op::Time) p.uses_time = true;
    };
    for (size_t i = 0; i < n; ++i) {
        if (!sel[i].emit) continue;
        const Sel& s = sel[i];
        if (g.is_const(static_cast<NodeId>(i)) && roots.end() == std::find(roots.begin(), roots.end(), i))
            continue;  // materialised just before its first user
        for (NodeId arg : {s.a, s.b, s.c})
            if (arg != kNoNode && reg[arg] < 0) {
                // A constant operand without an immediate form: load it now. Its last use
                // is recorded relative to node order, which is after this point.
                emit(arg, Sel{Op::Const, kNoNode, kNoNode, kNoNode, g.const_value(arg), true});
            }
        emit(static_cast<NodeId>(i), s);
    }
    p.num_regs = pool.used();
    for (NodeId r : roots) {
        if (reg[r] < 0) emit(r, Sel{Op::Const, kNoNode, kNoNode, kNoNode, g.const_value(r), true});
        p.outputs.push_back(static_cast<uint16_t>(reg[r]));
    }
    p.num_regs = pool.used();
    p.output_names = names;
    p.output_names.resize(roots.size());
    for (size_t i = 0; i < roots.size(); ++i)
        if (p.output_names[i].empty()) p.output_names[i] = fmt::format("out{}", i);
    return p;
}

}  // namespace sdfc
