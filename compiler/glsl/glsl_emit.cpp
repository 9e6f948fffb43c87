// Programs -> GLSL functions (see compiler/glsl/glsl_emit.hpp). Every instruction's text comes
// from its row of compiler/ir/opcodes.def; nothing here knows what an opcode means.
#include "compiler/glsl/glsl_emit.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

namespace sdfc::glsl {

std::string literal(float v) {
    if (std::isnan(v)) return "uintBitsToFloat(0x7fc00000u)";
    if (std::isinf(v)) return v > 0 ? "uintBitsToFloat(0x7f800000u)" : "(-uintBitsToFloat(0x7f800000u))";
    char buf[64];
    auto res = std::to_chars(buf, buf + sizeof buf, v);  // shortest text that reads back as v
    std::string s(buf, res.ptr);
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    if (s[0] == '-') s = "(" + s + ")";
    return s;
}

namespace {

int count_placeholder(std::string_view tmpl, std::string_view ph) {
    int n = 0;
    for (size_t p = tmpl.find(ph); p != std::string_view::npos; p = tmpl.find(ph, p + ph.size())) ++n;
    return n;
}

// "(x + y)" -> "x + y" when the outer parentheses enclose the whole text.
std::string strip_outer(const std::string& s) {
    if (s.size() < 2 || s.front() != '(' || s.back() != ')') return s;
    int depth = 0;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '(') ++depth;
        else if (s[i] == ')' && --depth == 0 && i + 1 != s.size()) return s;
    }
    return s.substr(1, s.size() - 2);
}

bool is_atom(Op op) { return op == Op::Const || is_input(op); }

}  // namespace

namespace {

// "(-2.5)" as literal() writes negative numbers.
bool is_negative_literal(std::string_view s) {
    if (s.size() < 4 || s[0] != '(' || s[1] != '-' || s.back() != ')') return false;
    return s.substr(2, s.size() - 3).find_first_not_of("0123456789.e+-") == std::string_view::npos;
}

// Appends an operand; "x + (-2.5)" is written "x - 2.5" and "x - (-2.5)" "x + 2.5" (the same
// IEEE result: negation is exact).
void append_operand(std::string& out, std::string_view v) {
    const bool plus = out.size() >= 3 && out.compare(out.size() - 3, 3, " + ") == 0;
    const bool minus = out.size() >= 3 && out.compare(out.size() - 3, 3, " - ") == 0;
    if ((plus || minus) && is_negative_literal(v)) {
        out[out.size() - 2] = plus ? '-' : '+';
        out += v.substr(2, v.size() - 3);
        return;
    }
    out += v;
}

}  // namespace

std::string op_expr(Op op, std::string_view a, std::string_view b, std::string_view c, float k) {
    std::string_view t = op_info(op).glsl;
    std::string out;
    out.reserve(t.size() + a.size() * 2 + b.size() + c.size() + 16);
    for (size_t i = 0; i < t.size();) {
        if (t[i] == '{' && i + 2 < t.size() && t[i + 2] == '}') {
            switch (t[i + 1]) {
                case 'a': append_operand(out, a); i += 3; continue;
                case 'b': append_operand(out, b); i += 3; continue;
                case 'c': append_operand(out, c); i += 3; continue;
                case 'k': append_operand(out, literal(k)); i += 3; continue;
                default: break;
            }
        }
        out += t[i++];
    }
    return out;
}

std::string comment_text(std::string_view s) {
    std::string out;
    for (char ch : s) {
        unsigned char u = static_cast<unsigned char>(ch);
        if (u == '\t') out += ' ';
        else if (u < 0x20 || u >= 0x7f) out += (u >= 0x80 && (u & 0xC0) != 0x80) ? "?" : "";  // one '?' per UTF-8 character
        else out += ch;
    }
    for (size_t p; (p = out.find("</")) != std::string::npos;) out.replace(p, 2, "< /");
    for (size_t p; (p = out.find("<!")) != std::string::npos;) out.replace(p, 2, "< !");
    while (!out.empty() && (out.back() == '\\' || out.back() == ' ')) out.pop_back();
    size_t b = out.find_first_not_of(' ');
    return b == std::string::npos ? std::string() : out.substr(b);
}

bool uses_op(const Program& prog, Op op) {
    for (const Instr& in : prog.code)
        if (in.op == op) return true;
    return false;
}

std::string op_helpers(std::initializer_list<const Program*> progs) {
    auto uses = [&](std::initializer_list<Op> ops) {
        for (const Program* p : progs)
            for (Op op : ops)
                if (uses_op(*p, op)) return true;
        return false;
    };
    std::string out;
    if (uses({Op::Noise3})) {
        out += "\n// Gradient noise, bit for bit the CPU's (compiler/ir/op_math.hpp).\n";
        out += om::kGlslNoise;
    }
    if (uses({Op::Pow, Op::PowI, Op::Atan2})) {
        out += "\n// pow and atan2 as the CPU computes them (compiler/ir/pow.glsl).\n";
        out += om::kGlslPow;
    }
    return out;
}

std::string function(const Program& prog, const FunctionSpec& spec) {
    const size_t n = prog.code.size();
    // Definitions: which instruction last wrote each register, as the VM would run it.
    std::vector<int> uses(n, 0);
    std::vector<uint8_t> dup(n, 0);
    std::vector<int> cur(prog.num_regs + 1, -1);
    static constexpr std::string_view kPh[3] = {"{a}", "{b}", "{c}"};
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = prog.code[i];
        const OpInfo& info = op_info(in.op);
        const uint16_t regs[3] = {in.a, in.b, in.c};
        for (int s = 0; s < info.arity; ++s) {
            int d = regs[s] < cur.size() ? cur[regs[s]] : -1;
            if (d < 0) continue;
            ++uses[d];
            if (count_placeholder(info.glsl, kPh[s]) > 1) dup[d] = 1;
        }
        if (in.out < cur.size()) cur[in.out] = static_cast<int>(i);
    }
    for (uint16_t o : prog.outputs)
        if (o < cur.size() && cur[o] >= 0) ++uses[cur[o]];

    std::string body;
    std::vector<std::string> expr(n);
    std::fill(cur.begin(), cur.end(), -1);
    auto operand = [&](uint16_t reg) -> std::string {
        int d = reg < cur.size() ? cur[reg] : -1;
        return d >= 0 ? expr[d] : std::string("0.0");
    };
    const SourceFile* last_file = nullptr;
    uint32_t last_line = 0;
    int counter = 0;
    for (size_t i = 0; i < n; ++i) {
        const Instr& in = prog.code[i];
        const OpInfo& info = op_info(in.op);
        std::string a = info.arity > 0 ? operand(in.a) : "", b = info.arity > 1 ? operand(in.b) : "",
                    c = info.arity > 2 ? operand(in.c) : "";
        std::string text = op_expr(in.op, a, b, c, in.k);
        if (in.op == Op::Copy) text = a;
        if (is_atom(in.op) || in.op == Op::Copy || (uses[i] == 1 && !dup[i] && text.size() <= spec.inline_limit) ||
            uses[i] == 0) {
            expr[i] = std::move(text);
        } else {
            // The script line an instruction comes from ends its statement's line, once a line.
            std::string note;
            const bool quiet = i < prog.locs.size() && prog.locs[i].file == spec.quiet.file && prog.locs[i].line == spec.quiet.line &&
                               prog.locs[i].col == spec.quiet.col;
            if (i < prog.locs.size() && prog.locs[i].known() && !quiet &&
                (prog.locs[i].file != last_file || prog.locs[i].line != last_line)) {
                const Loc& l = prog.locs[i];
                last_file = l.file, last_line = l.line;
                std::string src = comment_text(l.file->line(l.line));
                if (src.rfind("//", 0) == 0 || src.rfind("/*", 0) == 0) src.clear();  // a comment line: the file's top level
                if (src.size() > 90) src = src.substr(0, 87) + "...";
                note = fmt::format("  // {}:{}{}{}", comment_text(std::filesystem::path(l.file->path).filename().string()), l.line,
                                   src.empty() ? "" : "  ", src);
            }
            std::string name = fmt::format("{}{}", spec.var_prefix, counter++);
            body += fmt::format("{}float {} = {};{}\n", spec.indent, name, strip_outer(text), note);
            expr[i] = std::move(name);
        }
        if (in.out < cur.size()) cur[in.out] = static_cast<int>(i);
    }
    std::vector<std::string> outs;
    for (uint16_t o : prog.outputs) outs.push_back(strip_outer(operand(o)));
    std::string out = spec.signature + " {\n" + body;
    if (spec.finish) {
        for (const std::string& line : spec.finish(outs)) out += spec.indent + line + "\n";
    } else if (!outs.empty()) {
        out += spec.indent + "return " + outs[0] + ";\n";
    }
    out += "}\n";
    return out;
}

}  // namespace sdfc::glsl
