// The disassembler (`sdfc compile --emit bytecode`, the golden listings): one line per
// instruction with its source line, as clox's debug.c prints them.
#include <fmt/format.h>

#include "compiler/bytecode/program.hpp"

namespace sdfc {

std::string disassemble(const Program& p) {
    std::string out = fmt::format("; {} instructions, {} registers\n", p.code.size(), p.num_regs);
    for (size_t i = 0; i < p.code.size(); ++i) {
        const Instr& in = p.code[i];
        const OpInfo& info = op_info(in.op);
        std::string line = fmt::format("{:04}  {:<9} r{}", i, info.mnemonic, in.out);
        const uint16_t ops[3] = {in.a, in.b, in.c};
        for (int j = 0; j < info.arity; ++j) line += fmt::format(", r{}", ops[j]);
        if (info.has_imm) line += fmt::format(", {}", in.k);
        if (in.op == Op::Guard && guard_index(in) < p.guards.size()) {
            const Guard& gd = p.guards[guard_index(in)];
            line += fmt::format(" at r{} r{} r{} in [{}, {}, {}]..[{}, {}, {}] to {:04}", gd.px, gd.py, gd.pz, gd.lo[0], gd.lo[1], gd.lo[2],
                                gd.hi[0], gd.hi[1], gd.hi[2], gd.end);
        }
        if (i < p.locs.size() && p.locs[i].known()) line = fmt::format("{:<44}; line {}", line, p.locs[i].line);
        out += line;
        out += '\n';
    }
    for (size_t i = 0; i < p.outputs.size(); ++i)
        out += fmt::format("; output {} = r{}\n", p.output_names[i], p.outputs[i]);
    return out;
}

}  // namespace sdfc
