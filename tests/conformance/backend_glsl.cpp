// The GLSL adapter of backends.hpp: a case's program through the project's emitter
// (glsl::function) into a fragment shader run by Mesa llvmpipe. Pixel i reads point i from
// an RGBA32F texture and writes the float's four bytes as RGBA8, so the value comes back
// exactly. Built without EGL (SDFC_HAVE_EGL unset), it reports itself unavailable.
#include "conformance/backends.hpp"

#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "compiler/glsl/glsl_emit.hpp"
#include "compiler/glsl/glsl_tape.hpp"

#if SDFC_HAVE_EGL
#include "gpu/gles.hpp"
#endif

namespace sdfc::conformance {

#if SDFC_HAVE_EGL

namespace {

constexpr int kWidth = 64;  // pixels a row; rows as many as the points need

struct Context {
    gpu_test::Gles gles;
    std::string why;  // "" when ready
    GLuint points = 0;
    Context() {
        why = gles.init();
        if (why.empty()) glGenTextures(1, &points);
    }
};

Context& context() {
    static Context c;
    return c;
}

// `tape`: the program through the tape interpreter (compiler/glsl/glsl_tape.hpp, its tape a
// constant array) instead of straight-line code.
std::string shader(const Program& p, bool tape) {
    glsl::FunctionSpec spec;
    spec.signature = "float sdf_case(vec3 p)";
    spec.var_prefix = "v";
    std::string s = "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler2D;\n"
                    "uniform sampler2D sdf_points;\nuniform float sdf_time_in;\nfloat sdf_time;\nout vec4 sdf_bytes;\n"
                    "const float sdf_param[4] = float[4](0.0, 0.0, 0.0, 0.0);  // (the params' values are 0)\n";
    s += glsl::op_helpers({&p});
    if (tape) {
        const glsl::PackedTapes t = glsl::pack_tapes({&p});
        s += glsl::tape_interpreter(t, glsl::TapeStorage::ConstArray);
        s += fmt::format("float sdf_case(vec3 p) {{\n    sdf_run({}, {}, p);\n    return sdf_reg[{}];\n}}\n", t.segments[0].begin,
                         t.segments[0].end, t.segments[0].outputs.at(0));
    } else {
        s += glsl::function(p, spec);
    }
    s += "void main() {\n"
         "    sdf_time = sdf_time_in;\n"
         "    uint u = floatBitsToUint(sdf_case(texelFetch(sdf_points, ivec2(gl_FragCoord.xy), 0).xyz));\n"
         "    sdf_bytes = vec4(uvec4(u, u >> 8, u >> 16, u >> 24) & 255u) / 255.0;\n"
         "}\n";
    return s;
}

}  // namespace

std::string GlslLlvmpipe::unavailable() const { return context().why; }

std::vector<float> GlslLlvmpipe::eval(const Program& p, const std::vector<Point>& pts, float time) { return run(p, pts, time, false); }

std::vector<float> GlslLlvmpipe::run(const Program& p, const std::vector<Point>& pts, float time, bool tape) {
    Context& c = context();
    const int rows = int((pts.size() + kWidth - 1) / kWidth);
    std::vector<float> texels(size_t(kWidth) * size_t(rows) * 4, 0.0f);
    for (size_t i = 0; i < pts.size(); ++i) texels[i * 4] = pts[i].x, texels[i * 4 + 1] = pts[i].y, texels[i * 4 + 2] = pts[i].z;
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, c.points);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, kWidth, rows, 0, GL_RGBA, GL_FLOAT, texels.data());
    std::vector<uint8_t> rgba;
    error = c.gles.draw(shader(p, tape), kWidth, rows, rgba, [&](GLuint prog) {
        glUniform1i(glGetUniformLocation(prog, "sdf_points"), 0);
        glUniform1f(glGetUniformLocation(prog, "sdf_time_in"), time);
    });
    if (!error.empty()) {
        error += "\nshader:\n" + shader(p, tape);
        return {};
    }
    std::vector<float> out(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) {
        const uint32_t u = uint32_t(rgba[i * 4]) | uint32_t(rgba[i * 4 + 1]) << 8 | uint32_t(rgba[i * 4 + 2]) << 16 |
                           uint32_t(rgba[i * 4 + 3]) << 24;
        std::memcpy(&out[i], &u, sizeof u);
    }
    return out;
}

#else

std::string GlslLlvmpipe::unavailable() const { return "built without EGL/GLESv2 (Debian: libegl-dev libgles-dev)"; }
std::vector<float> GlslLlvmpipe::eval(const Program&, const std::vector<Point>&, float) { return {}; }
std::vector<float> GlslLlvmpipe::run(const Program&, const std::vector<Point>&, float, bool) { return {}; }

#endif

std::string GlslLlvmpipe::known_difference(const Case& c, const Point& p, float got) {
    if (c.kind != Case::Opcode || c.expect.empty()) return "";
    const float a = p.x;
    const float want = eval_op(c.op, p.x, p.y, p.z, c.k);
    const float err = std::fabs(got - want);
    switch (c.op) {
        case Op::Asin:
        case Op::Acos:
            return err <= 1e-3f ? "asin/acos: llvmpipe's approximation is off by up to ~4e-4 (GLSL ES sets no precision)" : "";
        case Op::DivI:
        case Op::ModI:
            if (c.k == 0.0f && std::isnan(want)) return "0/0, mod(x, 0) with an immediate 0: Mesa folds 0 * y to 0 (GLSL ES need not give NaN)";
            if (c.op == Op::DivI) return "";
            [[fallthrough]];
        case Op::Mod:
            return err <= 0x1p-22f * std::fabs(a) ? "mod: x - y*floor(x/y) cancels; llvmpipe rounds it differently, within an ulp of x" : "";
        case Op::Noise3:
            return err <= 1e-5f ? "noise3: not the CPU's bits near lattice points (a few 1e-6; op_math.hpp promises equal bits)" : "";
        default: return "";
    }
}

}  // namespace sdfc::conformance
