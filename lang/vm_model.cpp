// The flat SSA format of the Prospero Challenge: `NAME OPCODE ARGS...` per line, `#`
// comments, the last line is the output. Read into the IR like any script's field.
#include <charconv>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include <fmt/format.h>

#include "lang/load.hpp"

namespace sdfc {

bool is_vm_path(const std::string& path) {
    return path.size() >= 3 && path.compare(path.size() - 3, 3, ".vm") == 0;
}

namespace {

struct VmOp {
    Op op;
    int arity;
};

bool vm_opcode(std::string_view name, VmOp& out) {
    static const std::unordered_map<std::string_view, VmOp> table = {
        {"var-x", {Op::VarX, 0}}, {"var-y", {Op::VarY, 0}}, {"var-z", {Op::VarZ, 0}}, {"const", {Op::Const, 0}},
        {"neg", {Op::Neg, 1}},    {"square", {Op::Square, 1}}, {"sqrt", {Op::Sqrt, 1}}, {"abs", {Op::Abs, 1}},
        {"exp", {Op::Exp, 1}},    {"ln", {Op::Log, 1}},       {"sin", {Op::Sin, 1}},   {"cos", {Op::Cos, 1}},
        {"add", {Op::Add, 2}},    {"sub", {Op::Sub, 2}},      {"mul", {Op::Mul, 2}},   {"div", {Op::Div, 2}},
        {"min", {Op::Min, 2}},    {"max", {Op::Max, 2}},
    };
    auto it = table.find(name);
    if (it == table.end()) return false;
    out = it->second;
    return true;
}

struct VmInstr {
    VmOp op;
    float k = 0;
    int a = -1, b = -1;
    Loc loc;
};

}  // namespace

Scene load_vm(SourceManager&, const SourceFile& file) {
    // Parse once into a small instruction list; the field closure replays it into whatever
    // graph asks (the compiler's), so constant folding and CSE apply as for scripts.
    auto instrs = std::make_shared<std::vector<VmInstr>>();
    std::unordered_map<std::string, int> names;
    bool uses_z = false;
    for (uint32_t ln = 1; ln <= file.line_starts.size(); ++ln) {
        std::string_view line = file.line(ln);
        size_t col0 = 0;
        while (col0 < line.size() && (line[col0] == ' ' || line[col0] == '\t')) ++col0;
        if (col0 == line.size() || line[col0] == '#') continue;
        std::vector<std::pair<std::string_view, uint32_t>> tok;
        size_t i = col0;
        while (i < line.size()) {
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
            size_t b = i;
            while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
            if (i > b) tok.emplace_back(line.substr(b, i - b), uint32_t(b + 1));
        }
        auto loc = [&](size_t t) { return Loc{&file, ln, t < tok.size() ? tok[t].second : uint32_t(col0 + 1)}; };
        if (tok.size() < 2) throw CompileError(loc(0), "expected `NAME OPCODE ARGS...`");
        VmInstr in;
        in.loc = loc(0);
        if (!vm_opcode(tok[1].first, in.op)) throw CompileError(loc(1), fmt::format("unknown opcode '{}'", tok[1].first));
        size_t want = 2 + (in.op.op == Op::Const ? 1 : size_t(in.op.arity));
        if (tok.size() != want)
            throw CompileError(loc(std::min(tok.size(), want) - (tok.size() > want ? 0 : 1)),
                               fmt::format("'{}' takes {} operand{}", tok[1].first, want - 2, want == 3 ? "" : "s"));
        if (in.op.op == Op::Const) {
            std::string s(tok[2].first);
            char* end = nullptr;
            in.k = std::strtof(s.c_str(), &end);
            if (end != s.c_str() + s.size()) throw CompileError(loc(2), fmt::format("'{}' is not a number", s));
            if (!std::isfinite(in.k)) throw CompileError(loc(2), fmt::format("'{}' is not a finite number", s));
        } else {
            for (int j = 0; j < in.op.arity; ++j) {
                auto it = names.find(std::string(tok[2 + j].first));
                if (it == names.end()) throw CompileError(loc(2 + j), fmt::format("unknown name '{}'", tok[2 + j].first));
                (j == 0 ? in.a : in.b) = it->second;
            }
        }
        if (in.op.op == Op::VarZ) uses_z = true;
        // (SSA: a name defined twice is a broken model, not a redefinition)
        const auto [at, fresh] = names.emplace(std::string(tok[0].first), int(instrs->size()));
        if (!fresh)
            throw CompileError(loc(0), fmt::format("'{}' is already defined (line {}): each name is defined once", tok[0].first,
                                                   (*instrs)[size_t(at->second)].loc.line));
        instrs->push_back(in);
    }
    if (instrs->empty()) throw CompileError(Loc{&file, 1, 1}, "the model has no operations");

    Scene s;
    s.graph = std::make_shared<Graph>();
    Graph& g = *s.graph;
    Shape f{ShapeKind::Field, Loc{&file, 1, 1}};
    f.field = [instrs](Graph& gr, const Vec3N& p) {
        std::vector<NodeId> v(instrs->size());
        for (size_t i = 0; i < instrs->size(); ++i) {
            const VmInstr& in = (*instrs)[i];
            gr.set_loc(in.loc);
            switch (in.op.op) {
                case Op::VarX: v[i] = p[0]; break;
                case Op::VarY: v[i] = p[1]; break;
                case Op::VarZ: v[i] = p[2]; break;
                case Op::Const: v[i] = gr.constant(in.k); break;
                default:
                    v[i] = in.op.arity == 1 ? gr.unary(in.op.op, v[size_t(in.a)]) : gr.binary(in.op.op, v[size_t(in.a)], v[size_t(in.b)]);
            }
            // A folded NaN or infinity (`ln` of -1) is an error on its own line, not on the
            // line of the next operation that uses it.
            if (gr.is_const(v[i]) && !std::isfinite(gr.const_value(v[i])))
                throw CompileError(in.loc, fmt::format("this operation is not a finite number ({})", shown_number(gr.const_value(v[i]))));
        }
        return v.back();
    };
    s.root = std::make_shared<const Shape>(std::move(f));
    s.is_2d = !uses_z;
    s.raw_field = true;
    set_default_settings(s);
    // Models live in [-1, 1]^3: a closer camera than a script's default.
    s.camera.position[2] = g.constant(3.5f);
    s.camera.fov = g.constant(40);
    s.ambient = {g.constant(0.08f), g.constant(0.08f), g.constant(0.08f)};
    s.background = {g.constant(0.02f), g.constant(0.02f), g.constant(0.03f)};
    s.render.width = 1024;
    s.render.height = 1024;
    s.render.max_distance = 20.0f;
    s.render.max_distance_set = true;
    return s;
}

Scene load_scene(SourceManager& sm, const std::string& path, const InterpretOptions& opts) {
    if (path == "-") return interpret_source(sm, sm.load_stdin(opts.limits.max_file_bytes), opts);
    if (is_vm_path(path)) {
        if (!opts.defines.empty()) throw DefineError(fmt::format("-D {}: a .vm model has no `let` to set", opts.defines.front().name));
        return load_vm(sm, sm.load(path, Loc{}, opts.limits.max_file_bytes));
    }
    return interpret_file(sm, path, opts);
}

}  // namespace sdfc
