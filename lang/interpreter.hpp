// The script interpreter: runs a parsed module (lets, defs, loops, recursion, imports) and
// produces the Scene. Numbers are evaluated symbolically into the IR Graph, so custom
// fields, `time` in GLSL and the point `p` are expressions, and script constants fold away.
#pragma once
#include <stdexcept>
#include <string>
#include <vector>
#include <optional>
#include <string>

#include "compiler/scene/scene.hpp"
#include "compiler/base/source.hpp"

namespace sdfc {

struct Limits {
    int max_recursion = 64;               // nested def calls
    size_t max_calls = 10000000;          // calls, field bodies and shapes applied to points, all together
    long max_loop_iterations = 100000;    // per for statement
    long max_total_iterations = 10000000; // all loops of a run together
    size_t max_shapes = 1000000;          // shapes built, and shapes in the scene tree (a shared one counts at each use)
    size_t max_list = 1000000;            // elements of one list (a value is ~140 bytes: concat doubling a list ate GBs)
    size_t max_ops = 20000000;            // IR nodes
    int max_nesting = 1024;               // syntax nesting (parser): a modifier and its block count 2
    int max_shape_depth = 4000;           // depth of the shape tree
    size_t max_file_bytes = 16u << 20;    // per source file
};

// `-D name=value` on the command line: the value (an expression) replaces the one of the
// main script's top-level `let name`.
struct Define {
    std::string name, value;
};

struct InterpretOptions {
    std::optional<float> time = 0.0f;  // nullopt: `time` stays symbolic (GLSL)
    Limits limits;
    std::vector<Define> defines;
};

// A -D the script cannot take (no such let, a value of another kind, not an expression):
// a command-line error, not the script's.
struct DefineError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Loads, parses and runs the script at `path`. Throws CompileError with every diagnostic
// found (independent errors in different statements are all reported).
Scene interpret_file(SourceManager& sm, const std::string& path, const InterpretOptions& opts = {});
Scene interpret_source(SourceManager& sm, const SourceFile& file, const InterpretOptions& opts = {});

}  // namespace sdfc
