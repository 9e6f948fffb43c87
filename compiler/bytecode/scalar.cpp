// The scalar reference evaluator: one point, one instruction at a time through eval_op
// (opcodes.def's semantics). Slow and obviously right: the conformance suite's reference,
// and what the GLSL backend samples a raw field with.
#include "compiler/bytecode/program.hpp"

#include <algorithm>
#include <cmath>

namespace sdfc {

bool guard_skips(const Program& p, const Instr& in, const float* r) {
    const Guard& gd = p.guards.at(guard_index(in));
    const float q[3] = {r[gd.px], r[gd.py], r[gd.pz]};
    float e2 = 0.0f;
    for (int i = 0; i < 3; ++i) {
        const float e = std::max(std::max(gd.lo[i] - q[i], q[i] - gd.hi[i]), 0.0f);
        e2 += e * e;
    }
    const float e = std::sqrt(e2);
    return e > 0.0f && e >= r[in.a];
}

std::vector<float> eval_scalar(const Program& p, float x, float y, float z, float time, bool skip) {
    std::vector<float> r(p.num_regs, 0.0f);
    for (size_t i = 0; i < p.code.size(); ++i) {
        const Instr& in = p.code[i];
        float v;
        if (in.op == Op::Guard && skip && guard_skips(p, in, r.data())) {
            r[in.out] = om::kSkipped;
            i = p.guards[guard_index(in)].end - 1;
            continue;
        }
        switch (in.op) {
            case Op::VarX: v = x; break;
            case Op::VarY: v = y; break;
            case Op::VarZ: v = z; break;
            case Op::Time: v = time; break;
            default: v = eval_op(in.op, r[in.a], r[in.b], r[in.c], in.k);
        }
        r[in.out] = v;
    }
    std::vector<float> out;
    for (uint16_t o : p.outputs) out.push_back(r[o]);
    return out;
}

void sample_scalar(const Program& p, const float* x, const float* y, const float* z, size_t n, float time, float* out) {
    if (p.outputs.empty()) return;
    for (size_t i = 0; i < n; ++i) out[i] = eval_scalar(p, x[i], y[i], z[i], time, false)[0];
}

}  // namespace sdfc
