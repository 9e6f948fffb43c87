// Scheduling guarded regions into blocks (schedule.hpp).
#include "compiler/bytecode/schedule.hpp"

#include <algorithm>

namespace sdfc {
namespace {

constexpr int32_t kTop = -1;

class Blocks {
public:
    Blocks(const Graph& g, const std::vector<uint8_t>& emit, const std::vector<std::array<NodeId, 3>>& args,
           const std::vector<NodeId>& roots, const std::vector<int32_t>& regions)
        : g_(g), G_(g.guards()), emit_(emit), args_(args), n_(g.size()) {
        claim_.assign(n_, -2);  // -2: not a region's root
        keep_.assign(G_.size(), 0);
        std::vector<uint8_t> is_root(n_, 0);
        for (NodeId r : roots) is_root[r] = 1;
        for (int32_t r : regions) {
            const NodeId d = G_[size_t(r)].root;
            if (d >= n_ || !emit_[d] || g.is_const(d) || is_root[d] || claim_[d] != -2) continue;
            keep_[size_t(r)] = 1;
            claim_[d] = r;
        }
        for (int32_t r : regions)
            if (keep_[size_t(r)])
                for (NodeId e : G_[size_t(r)].extra)
                    if (e < n_ && emit_[e] && !g.is_const(e) && !is_root[e] && claim_[e] == -2) claim_[e] = r;
        // Regions are made before what they hold, so a parent's index is below its children's.
        par_.assign(G_.size(), kTop);
        depth_.assign(G_.size(), 0);
        for (size_t r = 0; r < G_.size(); ++r) {
            if (!keep_[r]) continue;
            int32_t p = G_[r].parent;
            while (p >= 0 && !keep_[size_t(p)]) p = G_[size_t(p)].parent;
            par_[r] = p;
            depth_[r] = p >= 0 ? depth_[size_t(p)] + 1 : 1;
        }
        roots_ = roots;
    }

    std::vector<ScheduleStep> run() {
        if (!place()) return {};
        std::vector<ScheduleStep> out;
        out.reserve(n_ + 2 * G_.size());
        emit_block(kTop, out);
        if (!valid(out)) return {};
        return out;
    }

private:
    int depth(int32_t r) const { return r < 0 ? 0 : depth_[size_t(r)]; }
    int32_t lca(int32_t a, int32_t b) const {
        while (a != b) {
            if (depth(a) < depth(b)) std::swap(a, b);
            a = par_[size_t(a)];
        }
        return a;
    }
    // a lies in region r's subtree (or is r).
    bool within(int32_t a, int32_t r) const {
        if (r == kTop) return true;
        while (a != kTop && depth(a) > depth(r)) a = par_[size_t(a)];
        return a == r;
    }

    // Owners, from the last node back: every user of a node is decided before the node.
    bool place() {
        constexpr int32_t kNone = -3;
        std::vector<int32_t> use(n_, kNone);  // the LCA of the users' places so far
        auto add_use = [&](NodeId a, int32_t where) {
            if (a == kNoNode || a >= n_ || g_.is_const(a)) return;
            use[a] = use[a] == kNone ? where : lca(use[a], where);
        };
        for (NodeId r : roots_) add_use(r, kTop);
        for (size_t r = 0; r < G_.size(); ++r) {
            if (!keep_[r]) continue;
            add_use(G_[r].thr, par_[r]);
            for (NodeId q : G_[r].point) add_use(q, par_[r]);
        }
        owner_.assign(n_, kTop);
        for (size_t i = n_; i-- > 0;) {
            if (!emit_[i] || g_.is_const(NodeId(i))) continue;
            const int32_t c = claim_[i];
            int32_t o = use[i] == kNone ? kTop : use[i];
            if (c >= 0) {
                // A region's root: used in the region around it, not inside the region itself.
                if (!within(o, par_[size_t(c)]) || within(o, c)) return false;
                o = c;
            }
            owner_[i] = o;
            for (NodeId a : args_[i]) {
                if (a != kNoNode && a < n_ && claim_[a] >= 0 && within(o, claim_[a])) return false;  // a root read in its own block
                add_use(a, o);
            }
        }
        return true;
    }

    // Each region's nodes and sub-blocks, at the position of its last node.
    void emit_block(int32_t top, std::vector<ScheduleStep>& out) {
        const size_t R = G_.size();
        std::vector<std::vector<uint32_t>> nodes(R + 1);  // index r + 1 (0: the top)
        std::vector<uint32_t> pos(R, 0);
        for (size_t i = 0; i < n_; ++i) {
            if (!emit_[i] || g_.is_const(NodeId(i))) continue;
            nodes[size_t(owner_[i] + 1)].push_back(uint32_t(i));
            if (owner_[i] >= 0) pos[size_t(owner_[i])] = std::max(pos[size_t(owner_[i])], uint32_t(i));
        }
        for (size_t r = R; r-- > 0;)
            if (keep_[r] && par_[r] >= 0) pos[size_t(par_[r])] = std::max(pos[size_t(par_[r])], pos[r]);
        std::vector<std::vector<int32_t>> kids(R + 1);
        for (size_t r = 0; r < R; ++r)
            if (keep_[r] && pos[r] > 0) kids[size_t(par_[r] + 1)].push_back(int32_t(r));
        for (auto& k : kids) std::sort(k.begin(), k.end(), [&](int32_t a, int32_t b) { return pos[size_t(a)] < pos[size_t(b)]; });
        // Depth first with an explicit stack: nesting is as deep as the script's unions.
        struct Frame {
            int32_t r;
            size_t ni = 0, ki = 0;
        };
        std::vector<Frame> stack{{top}};
        while (!stack.empty()) {
            Frame& f = stack.back();
            const auto& ns = nodes[size_t(f.r + 1)];
            const auto& ks = kids[size_t(f.r + 1)];
            const bool more_nodes = f.ni < ns.size(), more_kids = f.ki < ks.size();
            if (!more_nodes && !more_kids) {
                if (f.r != top) out.push_back({ScheduleStep::End, uint32_t(f.r)});
                stack.pop_back();
                continue;
            }
            if (more_nodes && (!more_kids || ns[f.ni] < pos[size_t(ks[f.ki])])) {
                out.push_back({ScheduleStep::Node, ns[f.ni++]});
                continue;
            }
            const int32_t k = ks[f.ki++];
            out.push_back({ScheduleStep::Guard, uint32_t(k)});
            stack.push_back({k});
        }
    }

    // Every operand is computed before its use.
    bool valid(const std::vector<ScheduleStep>& steps) const {
        std::vector<uint8_t> done(n_, 0);
        auto ready = [&](NodeId a) { return a == kNoNode || a >= n_ || g_.is_const(a) || done[a]; };
        size_t count = 0;
        for (const ScheduleStep& s : steps) {
            if (s.kind == ScheduleStep::Node) {
                for (NodeId a : args_[s.id])
                    if (!ready(a)) return false;
                done[s.id] = 1;
                ++count;
            } else if (s.kind == ScheduleStep::Guard) {
                const GuardRegion& r = G_[s.id];
                if (!ready(r.thr)) return false;
                for (NodeId q : r.point)
                    if (!ready(q)) return false;
            }
        }
        size_t want = 0;
        for (size_t i = 0; i < n_; ++i) want += emit_[i] && !g_.is_const(NodeId(i));
        return count == want;
    }

    const Graph& g_;
    const std::vector<GuardRegion>& G_;
    const std::vector<uint8_t>& emit_;
    const std::vector<std::array<NodeId, 3>>& args_;
    const size_t n_;
    std::vector<int32_t> claim_, par_, owner_;
    std::vector<int> depth_;
    std::vector<uint8_t> keep_;
    std::vector<NodeId> roots_;
};

}  // namespace

std::vector<ScheduleStep> schedule_guarded(const Graph& g, const std::vector<uint8_t>& emit,
                                           const std::vector<std::array<NodeId, 3>>& args, const std::vector<NodeId>& roots,
                                           const std::vector<int32_t>& regions) {
    if (regions.empty()) return {};
    return Blocks(g, emit, args, roots, regions).run();
}

}  // namespace sdfc
