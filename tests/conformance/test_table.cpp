// The opcode table itself (compiler/ir/opcodes.def, through the X-macro of opcodes.hpp): its
// rows are consistent with each other and with their GLSL templates, the disassembler names
// every row with its operands, and the interval code's choice ops are exactly min/max/select.
#include <catch2/catch.hpp>

#include <algorithm>
#include <string>

#include "compiler/bytecode/program.hpp"
#include "runtime/eval/interval.hpp"
#include "support.hpp"

using namespace sdfc;

TEST_CASE("the opcode table is consistent", "[opcodes]") {
    for (int o = 0; o < kOpCount; ++o) {
        const OpInfo& info = op_info(static_cast<Op>(o));
        INFO(info.mnemonic << " template " << info.glsl);
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

TEST_CASE("every opcode: the disassembler names it with its operands", "[opcodes]") {
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

TEST_CASE("is_choice_op: exactly the ops whose interval can pick a side", "[opcodes][interval]") {
    for (int o = 0; o < kOpCount; ++o) {
        const Op op = static_cast<Op>(o);
        const bool want = op == Op::Min || op == Op::Max || op == Op::MinI || op == Op::MaxI || op == Op::Select;
        REQUIRE(is_choice_op(op) == want);
    }
}
