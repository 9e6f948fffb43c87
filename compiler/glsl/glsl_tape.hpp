// The scene's programs as data for the shader's tape interpreter (compiler/glsl/tape.glsl),
// the form of programs too long for straight-line GLSL: shader compilers take time and
// registers in proportion to straight-line code (Mesa llvmpipe: 30,000 instructions, 50 s),
// while the interpreter is the same ~100 lines for any scene. Its dispatch is generated
// from opcodes.def's GLSL templates, so it is the straight-line emitter's twin.
//
// Layout: a flat array of 32-bit words, read two at a time (a "slot"; a uvec4 holds two).
//   narrow (every program under 256 registers), one slot an instruction:
//     w0 = op | out << 8 | a << 16 | b << 24      w1 = k's bits (ops with an immediate), else c
//   wide (256 registers or more), two slots an instruction:
//     w0 = op, w1 = out, w2 = a | b << 16, w3 = k's bits or c
// Programs lie one after another; each is a segment [begin, end) of instruction indices
// (slots in narrow, pairs of slots in wide), run by sdf_run(begin, end, p).
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/bytecode/program.hpp"

namespace sdfc::glsl {

struct TapeSegment {
    uint32_t begin = 0, end = 0;       // instructions
    std::vector<uint16_t> outputs;     // register of each output
};

struct PackedTapes {
    bool wide = false;
    uint32_t num_regs = 1;             // the register file sdf_run needs (the largest program's)
    std::vector<uint32_t> words;       // the tape, padded to whole uvec4s
    std::vector<TapeSegment> segments; // one per program, in the order given
    std::vector<Op> ops;               // the opcodes the tape uses (the interpreter's cases)
};

PackedTapes pack_tapes(const std::vector<const Program*>& programs);

// Where the shader reads the tape from.
enum class TapeStorage {
    ConstArray,  // `const uvec4 SDF_TAPE[N]` in the shader (Shadertoy, GLSL 330)
    Texture,     // `uniform usampler2D sdf_tape`, RGBA32UI, kTapeTextureWidth texels a row (the html page)
};
inline constexpr int kTapeTextureWidth = 1024;  // texels (uvec4) a row

// The interpreter's text: the tape (as a constant array) or its sampler, the register file,
// sdf_fetch and sdf_run with a case for each opcode the tape uses.
std::string tape_interpreter(const PackedTapes& t, TapeStorage storage);

// The rows of the sdf_tape texture that holds `texels` (at least one).
inline size_t tape_texture_rows(size_t texels) {
    return std::max<size_t>(1, (texels + kTapeTextureWidth - 1) / kTapeTextureWidth);
}
// The words padded with zeros to the whole texture (tape_texture_rows), as uploaded.
std::vector<uint32_t> tape_texture_words(const std::vector<uint32_t>& words);

// The words as little-endian bytes (the data of `sdfc glsl --tape-file`).
std::string tape_bytes(const std::vector<uint32_t>& words);
// ... as base64, for the html page's texture.
std::string tape_base64(const std::vector<uint32_t>& words);

}  // namespace sdfc::glsl
