// Helpers shared by the test suites: compile a script from a string, evaluate distances,
// capture the first diagnostic.
#pragma once
#include <cmath>
#include <string>

#include "compiler/bytecode/compile.hpp"
#include "compiler/render/plan.hpp"
#include "lang/interpreter.hpp"
#include "runtime/io/image.hpp"
#include "runtime/eval/vm.hpp"

namespace sdfc::test {

// A linear value as the 8-bit sRGB level a PNG would hold (0 .. 255).
inline float srgb8(float v) {
    v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);  // (NaN stays NaN)
    const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
    return std::round(s * 255.0f);
}

// PSNR of two pictures of the same size as 8-bit sRGB (what PNGs would hold), in dB; 200
// when they are the same.
inline double psnr_srgb8(const Image& a, const Image& b) {
    double se = 0.0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const double d = (srgb8(a.pixels[i]) - srgb8(b.pixels[i])) / 255.0;
        se += d * d;
    }
    const double mse = se / static_cast<double>(a.pixels.size());
    return mse == 0.0 ? 200.0 : 10.0 * std::log10(1.0 / mse);
}

struct Compiled {
    SourceManager sm;
    Scene scene;
    CompiledScene cs;
};

// Compiles `src` as if it were the file `name`. Throws CompileError.
inline std::unique_ptr<Compiled> compile_text(const std::string& src, const std::string& name = "test.sdf",
                                              InterpretOptions opts = {}) {
    auto c = std::make_unique<Compiled>();
    const SourceFile& f = c->sm.add(name, src);
    c->scene = interpret_source(c->sm, f, opts);
    c->cs = compile_scene(c->scene);
    // Tests adjust the lights of compiled scenes: give scripts without a light the rig the
    // render plan would use (the picture is the same).
    if (c->cs.lights.empty()) c->cs.lights = default_lights(c->cs.camera);
    return c;
}

// out := op(r0, r1, r2, k) with r0..r2 = x, y, z: one opcode alone, for walking the opcode
// table through every backend.
// A guard over the cube [lo, hi]^3 around the point in registers 0, 1, 2, its region ending
// before instruction `end`.
inline Guard cube_guard(float lo, float hi, uint32_t end) {
    Guard g;
    g.px = 0, g.py = 1, g.pz = 2;
    g.lo[0] = g.lo[1] = g.lo[2] = lo;
    g.hi[0] = g.hi[1] = g.hi[2] = hi;
    g.end = end;
    return g;
}

inline Program single_op_program(Op op, float k) {
    Program p;
    p.code.push_back(Instr{Op::VarX, 0, 0});
    p.code.push_back(Instr{Op::VarY, 0, 1});
    p.code.push_back(Instr{Op::VarZ, 0, 2});
    Instr in{op};
    in.out = 3, in.a = 0, in.b = 1, in.c = 2, in.k = k;
    if (op == Op::Guard) {  // a guard whose region is empty: +inf whether it skips or not
        in.k = 0.0f;
        p.guards.push_back(cube_guard(-1.0f, 1.0f, 4));
    }
    p.code.push_back(in);
    p.locs.resize(p.code.size());
    p.num_regs = 4;
    p.outputs = {3};
    p.output_names = {"out"};
    return p;
}

// Every value of every channel and AOV plane is finite (no NaN pixels).
// No NaN or infinity anywhere, but for +inf in depth, which marks a miss.
inline bool all_finite(const Image& img) {
    for (float v : img.pixels)
        if (!std::isfinite(v)) return false;
    for (const auto& a : img.aovs)
        for (float v : a.data)
            if (!std::isfinite(v) && !(a.name == "depth" && v == INFINITY)) return false;
    return true;
}

// The distance program at one point (batch VM, one lane).
inline float dist(const CompiledScene& cs, float x, float y, float z) {
    Evaluator ev(cs.distance);
    return ev.eval1(x, y, z, cs.time);
}

inline float dist_of(const std::string& src, float x, float y, float z) {
    auto c = compile_text(src);
    return dist(c->cs, x, y, z);
}

// The full formatted diagnostics of compiling `src`, or "" if it compiles.
inline std::string error_of(const std::string& src, const std::string& name = "test.sdf") {
    try {
        compile_text(src, name);
    } catch (const CompileError& e) {
        return e.formatted();
    }
    return "";
}

// Only the first line of the diagnostics.
inline std::string first_error_line(const std::string& src) {
    std::string e = error_of(src);
    return e.substr(0, e.find('\n'));
}

}  // namespace sdfc::test
