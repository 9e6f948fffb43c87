// Packing programs into the interpreter's tape, and the interpreter's text (glsl_tape.hpp).
#include "compiler/glsl/glsl_tape.hpp"

#include <algorithm>
#include <bit>

#include <fmt/format.h>

#include "compiler/glsl/tape.glsl.hpp"

namespace sdfc::glsl {

namespace {

uint32_t bits(float k) { return std::bit_cast<uint32_t>(k); }

void replace(std::string& s, std::string_view key, std::string_view value) {
    size_t p = s.find(key);
    if (p != std::string::npos) s.replace(p, key.size(), value);
}

// An opcode's GLSL template over the decoded operands: {a} {b} {c} are x y z, {k} is k.
std::string case_expr(Op op) {
    std::string_view t = op_info(op).glsl;
    std::string out;
    for (size_t i = 0; i < t.size();) {
        if (t[i] == '{' && i + 2 < t.size() && t[i + 2] == '}') {
            const char c = t[i + 1];
            if (c == 'a' || c == 'b' || c == 'c') {
                out += c == 'a' ? 'x' : c == 'b' ? 'y' : 'z';
                i += 3;
                continue;
            }
            if (c == 'k') {
                out += "k";
                i += 3;
                continue;
            }
        }
        out += t[i++];
    }
    return out;
}

// Cheap instructions a turn of the interpreter's loop: llvmpipe gives a shader's loops 65535
// turns in all (then leaves them), so a pixel runs at most 8 x 65535 of them there.
constexpr int kTapeUnroll = 8;

// Ops whose GLSL calls a function that costs tens of instructions (the transcendentals and
// the helpers of opcodes.def's templates), read off the template.
bool is_costly(Op op) {
    static constexpr std::string_view kCalls[] = {"sin(", "cos(", "tan(", "exp(", "log(", "sdf_"};
    for (std::string_view c : kCalls)
        if (op_info(op).glsl.find(c) != std::string_view::npos) return true;
    return false;
}

// The guard (program.hpp Guard): its region is skipped where the point is outside the box by
// at least the threshold x (its end is kb, a tape position); else the box is stepped over.
std::string guard_case(bool wide) {
    std::string read = wide ? "            uvec4 g1 = sdf_texel(pc + 1), g2 = sdf_texel(pc + 2);\n"
                              "            vec3 q = vec3(sdf_reg[int(g1.x & 65535u)], sdf_reg[int(g1.x >> 16)], sdf_reg[int(g1.y)]);\n"
                              "            vec3 lo = uintBitsToFloat(uvec3(g1.zw, g2.x)), hi = uintBitsToFloat(g2.yzw);\n"
                            : "            uvec4 g1 = sdf_texel((pc + 1) >> 1), g2 = sdf_texel((pc + 3) >> 1);\n"
                              "            if ((pc & 1) == 0) {\n"
                              "                uvec4 g3 = sdf_texel((pc + 5) >> 1);\n"
                              "                g1 = uvec4(g1.zw, g2.xy);\n"
                              "                g2 = uvec4(g2.zw, g3.xy);\n"
                              "            }\n"
                              "            vec3 q = vec3(sdf_reg[int(g1.x & 255u)], sdf_reg[int((g1.x >> 8) & 255u)], sdf_reg[int((g1.x >> 16) & 255u)]);\n"
                              "            vec3 lo = uintBitsToFloat(uvec3(g1.yzw)), hi = uintBitsToFloat(uvec3(g2.xyz));\n";
    return fmt::format(
        "case {}: {{  // guard: over its box and data, or to its region's end\n"
        "{}"
        "            float e = length(max(max(lo - q, q - hi), 0.0));\n"
        "            pc = e > 0.0 && e >= x ? int(kb) - 1 : pc + {};\n"
        "            v = uintBitsToFloat(0x7f800000u);\n"
        "            break;\n"
        "        }}\n",
        static_cast<int>(Op::Guard), read, wide ? 2 : 4);
}

// An instruction has room for three operands or two and k: length3_i (three and k) goes as
// length3 into its output register, then add_i of k there (the same two roundings).
constexpr bool only_length3i_has_four() {
    for (int i = 0; i < kOpCount; ++i)
        if (kOpInfo[i].arity == 3 && kOpInfo[i].has_imm && i != static_cast<int>(Op::Length3I)) return false;
    return true;
}
static_assert(only_length3i_has_four(), "pack_tapes splits length3_i only");

}  // namespace

PackedTapes pack_tapes(const std::vector<const Program*>& programs) {
    PackedTapes t;
    for (const Program* p : programs) t.num_regs = std::max(t.num_regs, p->num_regs);
    t.wide = t.num_regs > 256;
    // A guard takes 5 slots in narrow (the instruction, then its point registers and box),
    // 3 instructions' room in wide; jumps are to tape positions, so positions come first.
    const uint32_t guard_size = t.wide ? 3 : 5;
    std::vector<bool> used(kOpCount, false);
    uint32_t n = 0;
    for (const Program* p : programs) {
        std::vector<uint32_t> at(p->code.size() + 1);
        for (size_t i = 0; i < p->code.size(); ++i)
            at[i] = n, n += p->code[i].op == Op::Guard ? guard_size : (p->code[i].op == Op::Length3I ? 2 : 1);
        at[p->code.size()] = n;
        TapeSegment seg;
        seg.begin = at[0];
        seg.end = n;
        auto put = [&](const Instr& in) {
            used[static_cast<int>(in.op)] = true;
            const bool imm = op_info(in.op).has_imm;
            const uint32_t last = imm ? bits(in.k) : in.c;
            if (t.wide) {
                t.words.insert(t.words.end(), {static_cast<uint32_t>(in.op), in.out, uint32_t(in.a) | uint32_t(in.b) << 16, last});
            } else {
                t.words.push_back(static_cast<uint32_t>(in.op) | uint32_t(in.out) << 8 | uint32_t(in.a) << 16 | uint32_t(in.b) << 24);
                t.words.push_back(last);
            }
        };
        for (size_t i = 0; i < p->code.size(); ++i) {
            const Instr& in = p->code[i];
            if (in.op == Op::Length3I) {
                Instr len = in, add{Op::AddI};
                len.op = Op::Length3, len.k = 0.0f;
                add.out = add.a = in.out, add.k = in.k;
                put(len);
                put(add);
                continue;
            }
            used[static_cast<int>(in.op)] = true;
            if (in.op == Op::Guard) {
                const Guard& gd = p->guards.at(guard_index(in));
                const uint32_t end = at[gd.end];
                if (t.wide) {
                    t.words.insert(t.words.end(), {static_cast<uint32_t>(in.op), in.out, in.a, end, uint32_t(gd.px) | uint32_t(gd.py) << 16,
                                                   gd.pz, bits(gd.lo[0]), bits(gd.lo[1]), bits(gd.lo[2]), bits(gd.hi[0]), bits(gd.hi[1]),
                                                   bits(gd.hi[2])});
                } else {
                    t.words.insert(t.words.end(), {static_cast<uint32_t>(in.op) | uint32_t(in.out) << 8 | uint32_t(in.a) << 16, end,
                                                   uint32_t(gd.px) | uint32_t(gd.py) << 8 | uint32_t(gd.pz) << 16, bits(gd.lo[0]),
                                                   bits(gd.lo[1]), bits(gd.lo[2]), bits(gd.hi[0]), bits(gd.hi[1]), bits(gd.hi[2]), 0u});
                }
                continue;
            }
            put(in);
        }
        seg.outputs = p->outputs;
        t.segments.push_back(std::move(seg));
    }
    while (t.words.empty() || t.words.size() % 4 != 0) t.words.push_back(0);
    for (int i = 0; i < kOpCount; ++i)
        if (used[i]) t.ops.push_back(static_cast<Op>(i));
    return t;
}

std::string tape_interpreter(const PackedTapes& t, TapeStorage storage) {
    const size_t texels = t.words.size() / 4;
    std::string tape;
    if (storage == TapeStorage::ConstArray) {
        // Data, not code: eight uvec4s a line.
        tape = fmt::format("const uvec4 SDF_TAPE[{}] = uvec4[{}](", texels, texels);
        for (size_t i = 0; i < texels; ++i) {
            if (i % 8 == 0) tape += "\n    ";
            tape += fmt::format("uvec4({}u, {}u, {}u, {}u){}", t.words[4 * i], t.words[4 * i + 1], t.words[4 * i + 2], t.words[4 * i + 3],
                                i + 1 < texels ? ", " : "");
        }
        tape += ");\nuvec4 sdf_texel(int i) { return SDF_TAPE[i]; }";
    } else {
        tape = fmt::format(
            "uniform highp usampler2D sdf_tape;  // RGBA32UI, {} texels a row\n"
            "uvec4 sdf_texel(int i) {{ return texelFetch(sdf_tape, ivec2(i % {}, i / {}), 0); }}",
            kTapeTextureWidth, kTapeTextureWidth, kTapeTextureWidth);
    }
    // Operands are read once, before the switch; c's word holds k in ops with an immediate, so
    // its register number is clamped into the file.
    std::string decode;
    const std::string last_reg = std::to_string(t.num_regs - 1);
    if (t.wide) {
        decode =
            "    uvec4 w = sdf_texel(pc);\n"
            "    op = int(w.x);\n"
            "    o = int(w.y);\n"
            "    kb = w.w;\n"
            "    x = sdf_reg[int(w.z & 65535u)];\n"
            "    y = sdf_reg[int(w.z >> 16)];\n"
            "    z = sdf_reg[min(int(kb & 65535u), " + last_reg + ")];";
    } else {
        decode =
            "    uvec4 t = sdf_texel(pc >> 1);\n"
            "    uvec2 w = (pc & 1) == 0 ? t.xy : t.zw;\n"
            "    op = int(w.x & 255u);\n"
            "    o = int((w.x >> 8) & 255u);\n"
            "    kb = w.y;\n"
            "    x = sdf_reg[int((w.x >> 16) & 255u)];\n"
            "    y = sdf_reg[int(w.x >> 24)];\n"
            "    z = sdf_reg[min(int(kb & 255u), " + last_reg + ")];";
    }
    decode += "\n    k = uintBitsToFloat(kb);";
    std::string cheap, costly, test;
    for (Op op : t.ops) {
        std::string line =
            fmt::format("case {}: v = {}; break;  // {}\n", static_cast<int>(op), case_expr(op), op_info(op).mnemonic);
        if (op == Op::Guard) line = guard_case(t.wide);
        if (is_costly(op)) {
            costly += "            " + line;
            test += fmt::format("{}op == {}", test.empty() ? "" : " || ", static_cast<int>(op));
        } else {
            cheap += "        " + line;
        }
    }
    if (!cheap.empty()) cheap.pop_back();
    if (!costly.empty()) costly.pop_back();
    std::string s(kTapeGlsl);
    replace(s, "@DECODE@", decode);
    replace(s, "@COSTLY@", test.empty() ? "false" : test);
    replace(s, "@CHEAP_CASES@", cheap);
    replace(s, "@COSTLY_CASES@", costly);
    replace(s, "@REGS@", std::to_string(t.num_regs));
    std::string steps;
    for (int i = 0; i < kTapeUnroll; ++i) steps += "            sdf_step(pc, end, p, costly, op, o, x, y, z, k, kb);\n";
    steps.pop_back();
    replace(s, "@STEPS@", steps);
    replace(s, "@UNROLL@", std::to_string(kTapeUnroll));
    replace(s, "@TAPE@", tape);  // last: the data is not searched for keys
    return s;
}

std::vector<uint32_t> tape_texture_words(const std::vector<uint32_t>& words) {
    std::vector<uint32_t> data(tape_texture_rows(words.size() / 4) * kTapeTextureWidth * 4, 0u);
    std::copy(words.begin(), words.end(), data.begin());
    return data;
}

std::string tape_bytes(const std::vector<uint32_t>& words) {
    std::string bytes;
    bytes.reserve(words.size() * 4);
    for (uint32_t w : words)
        for (int i = 0; i < 4; ++i) bytes += static_cast<char>((w >> (8 * i)) & 255u);
    return bytes;
}

std::string tape_base64(const std::vector<uint32_t>& words) {
    static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const std::string bytes = tape_bytes(words);
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t b0 = uint8_t(bytes[i]), b1 = i + 1 < bytes.size() ? uint8_t(bytes[i + 1]) : 0u,
                       b2 = i + 2 < bytes.size() ? uint8_t(bytes[i + 2]) : 0u;
        const uint32_t v = b0 << 16 | b1 << 8 | b2;
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
    }
    return out;
}

}  // namespace sdfc::glsl
