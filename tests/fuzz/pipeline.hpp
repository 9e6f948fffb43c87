// One fuzz input through the whole pipeline, as `sdfc` runs it:
//   source checks -> parse (+ AST listing) -> interpret -> compile_scene -> batch VM at a
//   few points (both programs; the distance against the one-instruction-at-a-time
//   reference), a coarse mesh (closed and oriented: every directed edge once, its reverse
//   once), then the GLSL emitter on the scene built with a symbolic time.
// An input starting with "# vm" is read as a .vm model instead (`#` starts a comment
// there). The limits are small, so no input can legitimately run long or grow large: a
// timeout or running out of memory is a finding like a crash, a sanitizer report or a leak.
// (They are a tenth of what they were at first: inputs that hit them ran 1-2 s each under
// the sanitizers and took most of the fuzzing time, for paths a smaller input covers too.)
// Used by the libFuzzer target (fuzz_pipeline.cpp) and by the replay of the crashers kept
// in tests/fuzz/regressions/ (tests/lang/test_fuzz_regressions.cpp).
#pragma once
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "compiler/bytecode/compile.hpp"
#include "compiler/glsl/glsl.hpp"
#include "lang/ast.hpp"
#include "lang/interpreter.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"
#include "mesh/mesh_checks.hpp"
#include "runtime/mesh/mesh.hpp"

namespace sdfc::fuzz {

// Imports resolve next to a folder that does not exist, so only absolute paths reach files.
inline const char* const kPath = "/nonexistent/sdfc-fuzz/input.sdf";

inline InterpretOptions options(std::optional<float> time) {
    InterpretOptions o;
    o.time = time;
    Limits& l = o.limits;
    l.max_recursion = 32;
    l.max_calls = 5000;
    l.max_loop_iterations = 2000;
    l.max_total_iterations = 2000;
    l.max_shapes = 2000;
    l.max_ops = 20000;
    l.max_nesting = 64;
    l.max_shape_depth = 500;
    l.max_file_bytes = 1u << 20;
    return o;
}

// "" when the VM agrees with the reference evaluation, else what differs.
inline std::string evaluate(const CompiledScene& cs) {
    constexpr int n = 6;
    float x[n] = {0.0f, 1.0f, -3.0f, 1e3f, 0.1f, 2.5f};
    float y[n] = {0.0f, 0.5f, 2.0f, -1e3f, 1e-7f, -0.25f};
    float z[n] = {0.0f, -2.0f, 1.0f, 0.0f, -0.3f, 4.0f};
    Evaluator d(cs.distance);
    d.eval(x, y, z, n, cs.time);
    Evaluator s(cs.shading);
    s.eval(x, y, z, n, cs.time);
    for (int i = 0; i < n; ++i) {
        float ref = eval_scalar(cs.distance, x[i], y[i], z[i], cs.time).at(0);
        float got = d.output(0)[i];
        bool same = (std::isnan(ref) && std::isnan(got)) || ref == got ||
                    std::fabs(ref - got) <= 1e-4f * std::max(1.0f, std::fabs(ref));
        if (!same) return fmt::format("VM and eval_scalar differ at ({}, {}, {}): {} vs {}", x[i], y[i], z[i], got, ref);
    }
    return "";
}

// "" when a coarse mesh of the scene is closed and consistently oriented, and stays so
// simplified.
inline std::string mesh_check(const CompiledScene& cs) {
    if (cs.is_2d) return "";
    mesh::MeshOptions o;
    // A small interval search (custom fields): fuzzing stays fast.
    if (!mesh::default_box(cs, o.lo, o.hi, cs.time, 256)) o.lo = glm::vec3(-2.0f), o.hi = glm::vec3(2.0f);
    const glm::vec3 ext = o.hi - o.lo;
    if (!(std::max({ext.x, ext.y, ext.z}) < 1e30f)) return "";
    o.resolution = 6;
    o.max_triangles = 20000;
    o.time = cs.time;
    mesh::Mesh m;
    try {
        m = mesh::mesh_scene(cs, o);
    } catch (const std::runtime_error&) {  // over the triangle limit
        return "";
    }
    if (const size_t bad = test::bad_edges(m))  // the mesh tests' own check
        return fmt::format("the mesh is not closed and oriented ({} of its edges, {} triangles)", bad, m.triangles.size());
    // Simplified (to half a cell), it must stay so, and no vertex may be pinched.
    o.simplify = 0.5f * std::max({ext.x, ext.y, ext.z}) / float(o.resolution);
    const mesh::Mesh s = mesh::mesh_scene(cs, o);
    if (const size_t bad = test::bad_edges(s))
        return fmt::format("the simplified mesh is not closed and oriented ({} of its edges, {} triangles)", bad, s.triangles.size());
    if (const size_t pinched = test::pinched_vertices(s))
        return fmt::format("the simplified mesh has {} pinched vertices", pinched);
    return "";
}

// Runs `text` through the pipeline. A CompileError is the expected outcome of bad input;
// any other exception propagates. Returns "" or a description of a wrong result.
inline std::string run(const std::string& text) {
    const bool vm = text.rfind("# vm", 0) == 0;
    try {
        SourceManager sm;
        const SourceFile& f = sm.add(kPath, text);
        check_source_text(f);  // what SourceManager::load checks (NUL bytes, UTF-8)
        if (vm) {
            const CompiledScene cs = compile_scene(load_vm(sm, f));
            const std::string r = evaluate(cs);
            return r.empty() ? mesh_check(cs) : r;
        }
        (void)ast::dump(*ast::parse(f, ast::ParseOptions{options(0.0f).limits.max_nesting}));
        const CompiledScene cs = compile_scene(interpret_source(sm, f, options(0.5f)));
        std::string r = evaluate(cs);
        if (r.empty()) r = mesh_check(cs);
        if (!r.empty()) return r;
    } catch (const CompileError& e) {
        (void)e.formatted();
        return "";
    }
    try {
        SourceManager sm;
        const SourceFile& f = sm.add(kPath, text);
        (void)emit_glsl(interpret_source(sm, f, options(std::nullopt)), GlslTarget::Glsl330);
    } catch (const CompileError& e) {
        (void)e.formatted();
    }
    return "";
}

}  // namespace sdfc::fuzz
