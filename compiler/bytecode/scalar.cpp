// The scalar reference evaluator: one point, one instruction at a time through eval_op
// (opcodes.def's semantics). Slow and obviously right: the conformance suite's reference,
// and what the GLSL backend samples a raw field with.
#include "compiler/bytecode/program.hpp"

namespace sdfc {

std::vector<float> eval_scalar(const Program& p, float x, float y, float z, float time) {
    std::vector<float> r(p.num_regs, 0.0f);
    for (const Instr& in : p.code) {
        float v;
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
    for (size_t i = 0; i < n; ++i) out[i] = eval_scalar(p, x[i], y[i], z[i], time)[0];
}

}  // namespace sdfc
