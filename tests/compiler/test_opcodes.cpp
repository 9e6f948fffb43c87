// Every row of the opcode table through the backends built so far: the scalar semantics
// (constant folder), the batch VM on every lane, and the disassembler.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "compiler/bytecode/program.hpp"
#include "runtime/eval/vm.hpp"
#include "support.hpp"

using namespace sdfc;

namespace {

bool same(float a, float b) {
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    return a == b;
}

}  // namespace

TEST_CASE("every opcode: batch VM lanes equal the scalar semantics") {
    float xs[kBatch], ys[kBatch], zs[kBatch];
    for (int i = 0; i < kBatch; ++i) {
        // Values covering signs, zero, fractions and the [-1, 1] domain of asin/acos.
        xs[i] = -3.25f + 0.11f * float(i);
        ys[i] = 0.8f - 0.05f * float(i);
        zs[i] = (i % 3 == 0) ? 0.0f : 1.5f - 0.07f * float(i);
    }
    for (int o = 0; o < kOpCount; ++o) {
        Op op = static_cast<Op>(o);
        const OpInfo& info = op_info(op);
        const float k = 0.75f;
        Program p = test::single_op_program(op, k);
        Evaluator ev(p);
        ev.eval(xs, ys, zs, kBatch, 2.5f);
        for (int i = 0; i < kBatch; ++i) {
            float want;
            switch (op) {
                case Op::VarX: want = xs[i]; break;
                case Op::VarY: want = ys[i]; break;
                case Op::VarZ: want = zs[i]; break;
                case Op::Time: want = 2.5f; break;
                default: want = eval_op(op, xs[i], ys[i], zs[i], k);
            }
            INFO("opcode " << info.mnemonic << " lane " << i << ": vm " << ev.output(0)[i] << ", scalar " << want);
            // Vectorised libm and the scalar one may differ in the last ulp for transcendental ops.
            float got = ev.output(0)[i];
            REQUIRE((same(got, want) || std::fabs(got - want) <= 2e-6f * (1 + std::fabs(want))));
        }
        // eval_scalar (the reference interpreter) agrees too.
        auto ref = eval_scalar(p, xs[5], ys[5], zs[5], 2.5f);
        REQUIRE((same(ref[0], ev.output(0)[5]) || std::fabs(ref[0] - ev.output(0)[5]) <= 2e-6f * (1 + std::fabs(ref[0]))));
    }
}

TEST_CASE("every opcode: the disassembler names it with its operands") {
    for (int o = 0; o < kOpCount; ++o) {
        Op op = static_cast<Op>(o);
        const OpInfo& info = op_info(op);
        std::string text = disassemble(test::single_op_program(op, 0.75f));
        std::string line = "0003  " + std::string(info.mnemonic);
        INFO(text);
        REQUIRE(text.find(line) != std::string::npos);
        std::string operands = " r3";
        const char* regs[] = {", r0", ", r1", ", r2"};
        for (int j = 0; j < info.arity; ++j) operands += regs[j];
        if (info.has_imm) operands += ", 0.75";
        REQUIRE(text.find(std::string(info.mnemonic) + std::string(9 - std::min<size_t>(9, info.mnemonic.size()), ' ') + operands) !=
                std::string::npos);
    }
}

TEST_CASE("the opcode table is consistent") {
    for (int o = 0; o < kOpCount; ++o) {
        const OpInfo& info = op_info(static_cast<Op>(o));
        INFO(info.mnemonic);
        CHECK(info.arity >= 0);
        CHECK(info.arity <= 3);
        CHECK(!info.glsl.empty());
        // The GLSL template reads exactly the operands the row declares.
        CHECK((info.glsl.find("{a}") != std::string_view::npos) == (info.arity >= 1));
        CHECK((info.glsl.find("{b}") != std::string_view::npos) == (info.arity >= 2));
        CHECK((info.glsl.find("{c}") != std::string_view::npos) == (info.arity >= 3));
        CHECK((info.glsl.find("{k}") != std::string_view::npos) == info.has_imm);
        for (int p = 0; p < o; ++p) CHECK(op_info(static_cast<Op>(p)).mnemonic != info.mnemonic);
    }
}
