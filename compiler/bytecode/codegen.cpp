// IR Graph -> register Program: instruction selection (immediate forms, MulAddI and
// Length2I/3I fusion), then linear-scan register allocation in SSA order (the policy of
// regalloc.hpp).
#include <cmath>
#include <algorithm>
#include <limits>

#include <fmt/format.h>

#include "compiler/bytecode/program.hpp"
#include "compiler/bytecode/regalloc.hpp"
#include "compiler/bytecode/schedule.hpp"

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

namespace {

// Instruction selection over the live nodes: immediate forms, then Add(MulI(x), y) fused to
// MulAddI and AddI(Length2/3) to Length2I/3I where the inner op has no other use
// (`extra_uses`: uses by guards).
std::vector<Sel> select(const Graph& g, const std::vector<uint8_t>& live, const std::vector<NodeId>& roots,
                        const std::vector<NodeId>& extra_uses) {
    const size_t n = g.size();
    std::vector<Sel> sel(n);
    for (size_t i = 0; i < n; ++i) {
        if (!live[i]) continue;
        const Node& nd = g.node(static_cast<NodeId>(i));
        Sel s{nd.op, nd.a, nd.b, nd.c, nd.k, true};
        if (op_info(nd.op).arity == 2 && !op_info(nd.op).has_imm) {
            bool ca = g.is_const(nd.a), cb = g.is_const(nd.b);
            Op f; bool inv;
            // (x / 0 stays a division: its reciprocal would be an infinite immediate, and x / 0
            // is x's sign of infinity per point, as in Fidget's models and GLSL.)
            if (cb && imm_form(nd.op, 1, f, inv) && (!inv || std::isfinite(1.0f / g.const_value(nd.b)))) {
                float k = g.const_value(nd.b);
                s = Sel{f, nd.a, kNoNode, kNoNode, inv ? 1.0f / k : k, true};
            } else if (ca && imm_form(nd.op, 0, f, inv)) {
                s = Sel{f, nd.b, kNoNode, kNoNode, g.const_value(nd.a), true};
            }
        }
        sel[i] = s;
    }
    auto count_uses = [&](std::vector<uint32_t>& uses) {
        std::fill(uses.begin(), uses.end(), 0);
        for (size_t i = 0; i < n; ++i)
            if (sel[i].emit)
                for (NodeId arg : {sel[i].a, sel[i].b, sel[i].c})
                    if (arg != kNoNode) ++uses[arg];
        for (NodeId r : roots) ++uses[r];
        for (NodeId r : extra_uses) ++uses[r];
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
    // AddI(Length2/3(...)) -> Length2I/3I: a sphere's or a torus's distance in one instruction.
    for (size_t i = 0; i < n; ++i) {
        Sel& s = sel[i];
        if (!s.emit || s.op != Op::AddI || s.a == kNoNode) continue;
        const Sel& m = sel[s.a];
        if (!m.emit || uses[s.a] != 1 || (m.op != Op::Length2 && m.op != Op::Length3)) continue;
        s = Sel{m.op == Op::Length2 ? Op::Length2I : Op::Length3I, m.a, m.b, m.c, s.k, true};
    }
    count_uses(uses);
    for (size_t i = 0; i < n; ++i)
        if (sel[i].emit && uses[i] == 0) sel[i].emit = false;  // fused away
    return sel;
}

}  // namespace

Program codegen(const Graph& g, const std::vector<NodeId>& roots, const std::vector<std::string>& names) {
    const size_t n = g.size();
    // The graph's guarded regions whose root this program computes; their thresholds and
    // points are live too (a guard reads them).
    const std::vector<GuardRegion>& G = g.guards();
    std::vector<int32_t> regions;
    std::vector<NodeId> guard_inputs;
    const std::vector<uint8_t> live0 = reachable(g, roots);
    for (size_t r = 0; r < G.size() && r < 0xFFFF; ++r) {
        const GuardRegion& gr = G[r];
        if (gr.root >= n || !live0[gr.root] || gr.thr >= n) continue;
        bool ok = true;
        for (NodeId q : gr.point) ok &= q < n;
        if (!ok) continue;
        regions.push_back(int32_t(r));
        guard_inputs.push_back(gr.thr);
        for (NodeId q : gr.point) guard_inputs.push_back(q);
    }
    std::vector<NodeId> from = roots;
    from.insert(from.end(), guard_inputs.begin(), guard_inputs.end());
    std::vector<Sel> sel = select(g, regions.empty() ? live0 : reachable(g, from), roots, guard_inputs);
    std::vector<uint8_t> emit(n, 0);
    std::vector<std::array<NodeId, 3>> args(n, {kNoNode, kNoNode, kNoNode});
    for (size_t i = 0; i < n; ++i)
        if (sel[i].emit) emit[i] = 1, args[i] = {sel[i].a, sel[i].b, sel[i].c};
    std::vector<ScheduleStep> steps = schedule_guarded(g, emit, args, roots, regions);
    if (steps.empty()) {
        // Node order without guards: only what the outputs need.
        if (!regions.empty()) sel = select(g, live0, roots, {});
        for (size_t i = 0; i < n; ++i)
            if (sel[i].emit && !(g.is_const(NodeId(i)) && std::find(roots.begin(), roots.end(), i) == roots.end()))
                steps.push_back({ScheduleStep::Node, uint32_t(i)});
    }

    // Last use (step index); roots live to the end. A guard reads its threshold and point.
    constexpr uint32_t kForever = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> last(n, 0);
    for (uint32_t si = 0; si < steps.size(); ++si) {
        const ScheduleStep& st = steps[si];
        if (st.kind == ScheduleStep::Node) {
            const Sel& s = sel[st.id];
            for (NodeId arg : {s.a, s.b, s.c})
                if (arg != kNoNode) last[arg] = std::max(last[arg], si);
        } else if (st.kind == ScheduleStep::Guard) {
            last[G[st.id].thr] = std::max(last[G[st.id].thr], si);
            for (NodeId q : G[st.id].point) last[q] = std::max(last[q], si);
        }
    }
    for (NodeId r : roots) last[r] = kForever;

    Program p;
    std::vector<int32_t> reg(n, -1);  // -1: not in a register (a constant is loaded at its use)
    std::vector<uint16_t> free_stack;
    RegPool pool(free_stack, n + G.size() + 1);
    auto alloc = [&]() -> uint16_t {
        if (pool.exhausted()) throw CompileError(Loc{}, "the program needs more than 65535 registers");
        return pool.alloc();
    };
    uint32_t si = 0;  // the step being emitted
    // Constants loaded inside each open block: a skipped block loads nothing, so they are
    // loaded again where used after it.
    std::vector<std::vector<NodeId>> block_consts(1);
    std::vector<size_t> open_guards;  // code index of each open block's guard
    auto use_reg = [&](NodeId a) -> uint16_t {
        if (reg[a] < 0) {  // a constant: load it now
            Instr c{Op::Const};
            c.k = g.const_value(a);
            c.out = alloc();
            reg[a] = c.out;
            p.code.push_back(c);
            p.locs.push_back(g.node_loc(a));
            block_consts.back().push_back(a);
        }
        return static_cast<uint16_t>(reg[a]);
    };
    // Operands whose last use is this step are freed before the result takes a register,
    // so the result may reuse one (lane-wise ops are safe in place).
    auto release = [&](const NodeId (&ops)[4]) {
        for (int j = 0; j < 4; ++j) {
            NodeId a = ops[j];
            if (a == kNoNode || last[a] != si || reg[a] < 0) continue;
            bool dup = false;
            for (int q = 0; q < j; ++q) dup |= ops[q] == a;
            if (dup) continue;
            pool.release(static_cast<uint16_t>(reg[a]));
            reg[a] = -2;  // freed: nothing reads it again
        }
    };
    std::vector<int32_t> preset(n, -1);  // a region's root: the register its guard gave it
    for (; si < steps.size(); ++si) {
        const ScheduleStep& st = steps[si];
        if (st.kind == ScheduleStep::Node) {
            const Sel& s = sel[st.id];
            Instr in{s.op};
            in.k = s.k;
            uint16_t* slots[3] = {&in.a, &in.b, &in.c};
            NodeId ops[4] = {s.a, s.b, s.c, kNoNode};
            for (int j = 0; j < 3; ++j)
                if (ops[j] != kNoNode) *slots[j] = use_reg(ops[j]);
            release(ops);
            if (preset[st.id] >= 0) in.out = static_cast<uint16_t>(preset[st.id]);
            else in.out = alloc();
            reg[st.id] = in.out;
            p.code.push_back(in);
            p.locs.push_back(g.node_loc(st.id));
            if (s.op == Op::Time) p.uses_time = true;
        } else if (st.kind == ScheduleStep::Guard) {
            const GuardRegion& gr = G[st.id];
            Instr in{Op::Guard};
            in.a = use_reg(gr.thr);
            Guard gd;
            uint16_t pr[3];
            for (int j = 0; j < 3; ++j) pr[j] = use_reg(gr.point[j]);
            gd.px = pr[0], gd.py = pr[1], gd.pz = pr[2];
            for (int j = 0; j < 3; ++j) gd.lo[j] = gr.lo[j], gd.hi[j] = gr.hi[j];
            NodeId ops[4] = {gr.thr, gr.point[0], gr.point[1], gr.point[2]};
            release(ops);
            in.out = alloc();  // the region root's register from here on
            preset[gr.root] = in.out;
            in.k = static_cast<float>(p.guards.size());
            open_guards.push_back(p.code.size());
            p.guards.push_back(gd);
            p.code.push_back(in);
            p.locs.push_back(g.node_loc(gr.root));
            block_consts.emplace_back();
        } else {  // End
            const size_t gi = guard_index(p.code[open_guards.back()]);
            open_guards.pop_back();
            p.guards[gi].end = static_cast<uint32_t>(p.code.size());
            for (NodeId c : block_consts.back())
                if (reg[c] >= 0) {
                    pool.release(static_cast<uint16_t>(reg[c]));
                    reg[c] = -1;
                }
            block_consts.pop_back();
        }
    }
    for (NodeId r : roots) p.outputs.push_back(use_reg(r));
    p.num_regs = pool.used();
    p.output_names = names;
    p.output_names.resize(roots.size());
    for (size_t i = 0; i < roots.size(); ++i)
        if (p.output_names[i].empty()) p.output_names[i] = fmt::format("out{}", i);
    return p;
}

}  // namespace sdfc
