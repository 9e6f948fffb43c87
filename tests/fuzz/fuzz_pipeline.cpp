// libFuzzer target: one input through the whole pipeline, as `sdfc` runs it —
//   source checks -> parse -> interpret -> compile_scene -> batch VM at a few points
//   (both programs, and the scalar reference), and the GLSL emitter on the scene built
//   with a symbolic time.
// An input starting with "# vm" is read as a .vm model instead (a `#` line is a comment
// there). Limits are small, so no input can legitimately run long or grow large: a
// timeout or an out-of-memory is a finding like a crash, a sanitizer report or a leak.
// A CompileError is the expected outcome for bad input; any other exception escapes and
// is reported (every error a script causes must be a located diagnostic).
//
// Build (clang only):  CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -G Ninja \
//                        -DSDFC_FUZZ=ON -DSDFC_BUILD_TESTS=OFF && cmake --build build-fuzz
// Run:                 .ci/fuzz (seeds from examples/, the tests, tests/bad/, tests/fuzz/)
// Crashers go to tests/fuzz/regressions/, replayed by tests/lang/test_fuzz_regressions.cpp.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "compiler/compile.hpp"
#include "compiler/glsl.hpp"
#include "lang/ast.hpp"
#include "lang/interpreter.hpp"
#include "lang/load.hpp"
#include "runtime/vm.hpp"

using namespace sdfc;

namespace {

// Imports resolve next to a folder that does not exist, so only absolute paths reach files.
const char* const kPath = "/nonexistent/sdfc-fuzz/input.sdf";

InterpretOptions fuzz_options(std::optional<float> time) {
    InterpretOptions o;
    o.time = time;
    Limits& l = o.limits;
    l.max_recursion = 32;
    l.max_calls = 20000;
    l.max_loop_iterations = 10000;
    l.max_total_iterations = 10000;
    l.max_shapes = 20000;
    l.max_ops = 200000;
    l.max_nesting = 64;
    l.max_shape_depth = 500;
    l.max_file_bytes = 1u << 20;
    return o;
}

void evaluate(const CompiledScene& cs) {
    constexpr int n = 6;
    float x[n] = {0.0f, 1.0f, -3.0f, 1e3f, 0.1f, 2.5f};
    float y[n] = {0.0f, 0.5f, 2.0f, -1e3f, 1e-7f, -0.25f};
    float z[n] = {0.0f, -2.0f, 1.0f, 0.0f, -0.3f, 4.0f};
    Evaluator d(cs.distance);
    d.eval(x, y, z, n, cs.time);
    Evaluator s(cs.shading);
    s.eval(x, y, z, n, cs.time);
    // The batch VM and the one-instruction-at-a-time reference agree (NaN with NaN).
    for (int i = 0; i < n; ++i) {
        float ref = eval_scalar(cs.distance, x[i], y[i], z[i], cs.time).at(0);
        float got = d.output(0)[i];
        bool same = (std::isnan(ref) && std::isnan(got)) || ref == got ||
                    std::fabs(ref - got) <= 1e-4f * std::max(1.0f, std::fabs(ref));
        if (!same) {
            std::fprintf(stderr, "VM and eval_scalar differ at (%g, %g, %g): %.9g vs %.9g\n", x[i], y[i], z[i], got, ref);
            std::abort();
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    const bool vm = text.rfind("# vm", 0) == 0;
    try {
        SourceManager sm;
        const SourceFile& f = sm.add(kPath, text);
        check_source_text(f);  // what SourceManager::load checks (NUL bytes, UTF-8)
        if (vm) {
            Scene s = load_vm(sm, f);
            evaluate(compile_scene(s));
            return 0;
        }
        (void)ast::dump(*ast::parse(f, ast::ParseOptions{fuzz_options(0.0f).limits.max_nesting}));
        Scene s = interpret_source(sm, f, fuzz_options(0.5f));
        evaluate(compile_scene(s));
    } catch (const CompileError& e) {
        (void)e.formatted();
        return 0;
    }
    try {
        SourceManager sm;
        const SourceFile& f = sm.add(kPath, text);
        Scene s = interpret_source(sm, f, fuzz_options(std::nullopt));
        (void)emit_glsl(s, GlslTarget::Glsl330);
    } catch (const CompileError& e) {
        (void)e.formatted();
    }
    return 0;
}
