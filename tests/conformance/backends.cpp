// The CPU adapters of backends.hpp: the only code of the suite that calls eval_scalar, the
// batch VM, the interval evaluators and simplify.
#include "conformance/backends.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>

#include "runtime/eval/vm.hpp"

namespace sdfc::conformance {

std::vector<float> Scalar::eval(const Program& p, const std::vector<Point>& pts, float time) {
    std::vector<float> out;
    for (const Point& q : pts) out.push_back(eval_scalar(p, q.x, q.y, q.z, time)[0]);
    return out;
}

std::vector<float> BatchVm::eval(const Program& p, const std::vector<Point>& pts, float time) {
    Evaluator ev(p);
    std::vector<float> out(pts.size());
    for (size_t at = 0; at < pts.size(); at += kBatch) {
        const int n = int(std::min<size_t>(kBatch, pts.size() - at));
        float xs[kBatch], ys[kBatch], zs[kBatch];
        for (int i = 0; i < n; ++i) xs[i] = pts[at + i].x, ys[i] = pts[at + i].y, zs[i] = pts[at + i].z;
        ev.eval(xs, ys, zs, n, time);
        std::copy(ev.output(0), ev.output(0) + n, out.begin() + long(at));
    }
    return out;
}

// --- simplified tapes ---

namespace {

// Boxes at .. at + n of an IntervalEvaluator pass over `full`: their points through SweepVM,
// kBatch points of every box a sweep (a box with fewer repeats its last, as the VM pads).
void sweep_boxes(const Tape& full, const IntervalEvaluator& iv, int n, const std::vector<std::vector<Point>>& pts, size_t at,
                 float time, BatchScratch& batch, std::vector<std::vector<float>>& out) {
    const uint64_t all = n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
    simplify_masks(full, iv.choices(), iv.stride(), all, batch);
    if (!full.linked || full.out_def == Tape::kNone) throw std::runtime_error("a tape the sweep cannot follow");
    SweepVM sweep, one_a_pass(1);  // (the second runs its lanes in passes of one)
    std::vector<float> in(size_t(n) * 3 * kBatch);
    const float* xs[kIvLanes];
    const float* ys[kIvLanes];
    const float* zs[kIvLanes];
    for (size_t i = 0;; i += kBatch) {
        uint64_t lanes = 0;
        for (int l = 0; l < n; ++l) {
            const std::vector<Point>& q = pts[at + size_t(l)];
            if (i >= q.size()) continue;
            lanes |= uint64_t(1) << l;
            float* x = in.data() + size_t(l) * 3 * kBatch;
            for (int j = 0; j < kBatch; ++j) {
                const Point& pt = q[std::min(i + size_t(j), q.size() - 1)];
                x[j] = pt.x, x[kBatch + j] = pt.y, x[2 * kBatch + j] = pt.z;
            }
            xs[l] = x;
            ys[l] = x + kBatch;
            zs[l] = x + 2 * kBatch;
        }
        if (!lanes) return;
        sweep.eval(full, iv.choices(), iv.stride(), batch.mask.data(), lanes, xs, ys, zs, time);
        one_a_pass.eval(full, iv.choices(), iv.stride(), batch.mask.data(), lanes, xs, ys, zs, time);
        for (uint64_t r = lanes; r; r &= r - 1) {
            const int l = __builtin_ctzll(r);
            if (std::memcmp(sweep.output(l), one_a_pass.output(l), sizeof(float) * kBatch) != 0)
                throw std::runtime_error("the sweep's lanes run one a pass give other floats");
            const size_t m = std::min<size_t>(kBatch, pts[at + size_t(l)].size() - i);
            out[at + size_t(l)].insert(out[at + size_t(l)].end(), sweep.output(l), sweep.output(l) + m);
        }
    }
}

}  // namespace

template <Simplifier S>
std::vector<std::vector<float>> SimplifiedTape<S>::eval_in_boxes(const Program& p, const std::vector<Box>& boxes,
                                                                 const std::vector<std::vector<Point>>& pts, float time) {
    Tape full = Tape::from(p);
    if (S == Simplifier::SignOnly) full.mark_sign_only();
    if (S == Simplifier::MinChain) full.mark_min_chains();
    IntervalEvaluator iv(full.num_regs, full.choices);
    iv.keep_chains(S == Simplifier::MinChain);
    Evaluator ev(p);
    SimplifyScratch one;
    BatchScratch batch;
    Tape t;
    std::vector<std::vector<float>> out(boxes.size());
    for (size_t at = 0; at < boxes.size(); at += kIvLanes) {
        const int n = int(std::min<size_t>(kIvLanes, boxes.size() - at));
        float lo[3][kIvLanes], hi[3][kIvLanes];
        for (int l = 0; l < n; ++l) {
            const Box& b = boxes[at + size_t(l)];
            lo[0][l] = b.x.lo, hi[0][l] = b.x.hi, lo[1][l] = b.y.lo, hi[1][l] = b.y.hi, lo[2][l] = b.z.lo, hi[2][l] = b.z.hi;
        }
        iv.eval(full, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], n, time);
        iv.prune_min_chains(full, n);  // (only with keep_chains)
        if (S == Simplifier::Sweep) {
            sweep_boxes(full, iv, n, pts, at, time, batch, out);
            continue;
        }
        if (S != Simplifier::One)
            simplify_batch(full, iv.choices(), iv.stride(), n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1, batch,
                           S != Simplifier::BatchTrace);
        for (int l = 0; l < n; ++l) {
            const Instr* code;
            size_t len;
            uint32_t res, regs;
            if (S == Simplifier::One) {
                simplify(full, iv.choices(), iv.stride(), l, t, one);
                code = t.code.data(), len = t.code.size(), res = t.out, regs = t.num_regs;
            } else {
                code = batch.code(l), len = batch.len[size_t(l)], res = batch.out[size_t(l)], regs = batch.regs[size_t(l)];
            }
            // The VM's register file is sized for the full program.
            if (regs > p.num_regs) throw std::runtime_error("a simplified tape uses more registers than its program");
            const std::vector<Point>& q = pts[at + size_t(l)];
            for (size_t i = 0; i < q.size(); i += kBatch) {
                const int m = int(std::min<size_t>(kBatch, q.size() - i));
                float xs[kBatch], ys[kBatch], zs[kBatch];
                for (int j = 0; j < m; ++j) xs[j] = q[i + j].x, ys[j] = q[i + j].y, zs[j] = q[i + j].z;
                const uint16_t out_reg = uint16_t(res);
                const TapeView tape{code, uint32_t(len), &out_reg, 1, 0};
                ev.eval(tape, xs, ys, zs, m, time);
                out[at + size_t(l)].insert(out[at + size_t(l)].end(), ev.output(tape), ev.output(tape) + m);
            }
        }
    }
    return out;
}

template <Simplifier S>
std::vector<float> SimplifiedTape<S>::eval(const Program& p, const std::vector<Point>& pts, float time) {
    std::mt19937 rng(uint32_t(pts.size()) * 31u + 5u);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const float sizes[] = {0.0f, 1e-3f, 0.05f, 0.5f, 2.0f};
    std::vector<Box> boxes;
    std::vector<std::vector<Point>> one;
    for (const Point& q : pts) {
        const float s = sizes[rng() % std::size(sizes)];
        auto around = [&](float v) {
            const float lo = v - s * u(rng);
            return Interval{std::min(lo, v), std::max(lo + s, v)};
        };
        boxes.push_back({around(q.x), around(q.y), around(q.z)});
        one.push_back({q});
    }
    std::vector<float> out;
    for (const auto& v : eval_in_boxes(p, boxes, one, time)) out.push_back(v.at(0));
    return out;
}

template struct SimplifiedTape<Simplifier::One>;
template struct SimplifiedTape<Simplifier::BatchCompact>;
template struct SimplifiedTape<Simplifier::BatchTrace>;
template struct SimplifiedTape<Simplifier::SignOnly>;
template struct SimplifiedTape<Simplifier::MinChain>;
template struct SimplifiedTape<Simplifier::Sweep>;

// --- intervals ---

std::vector<BoxResult> ScalarInterval::eval(const Program& p, const std::vector<Box>& boxes, float time) {
    std::vector<BoxResult> out;
    std::vector<Interval> r(p.num_regs);
    for (const Box& b : boxes) {
        BoxResult res;
        for (const Instr& in : p.code) {
            Interval v;
            switch (in.op) {
                case Op::VarX: v = b.x; break;
                case Op::VarY: v = b.y; break;
                case Op::VarZ: v = b.z; break;
                case Op::Time: v = {time, time}; break;
                default: {
                    uint8_t choice = kChoiceBoth;
                    v = eval_interval(in.op, r[in.a], r[in.b], r[in.c], in.k, &choice);
                    if (is_choice_op(in.op)) res.choices.push_back(choice);
                }
            }
            r[in.out] = v;
        }
        res.value = r[p.outputs[0]];
        out.push_back(std::move(res));
    }
    return out;
}

std::vector<BoxResult> BatchInterval::eval(const Program& p, const std::vector<Box>& boxes, float time) {
    const Tape full = Tape::from(p);
    IntervalEvaluator iv(full.num_regs, full.choices);
    std::vector<BoxResult> out;
    for (size_t at = 0; at < boxes.size(); at += kIvLanes) {
        const int n = int(std::min<size_t>(kIvLanes, boxes.size() - at));
        float lo[3][kIvLanes], hi[3][kIvLanes];
        for (int l = 0; l < n; ++l) {
            const Box& b = boxes[at + size_t(l)];
            lo[0][l] = b.x.lo, hi[0][l] = b.x.hi, lo[1][l] = b.y.lo, hi[1][l] = b.y.hi, lo[2][l] = b.z.lo, hi[2][l] = b.z.hi;
        }
        iv.eval(full, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], n, time);
        for (int l = 0; l < n; ++l) {
            BoxResult res;
            res.value = iv.result(l);
            for (uint32_t s = 0; s < full.choices; ++s) res.choices.push_back(iv.choices()[size_t(s) * size_t(iv.stride()) + size_t(l)]);
            out.push_back(std::move(res));
        }
    }
    return out;
}

}  // namespace sdfc::conformance
