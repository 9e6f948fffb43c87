// Script values. Numbers, bools and vectors hold IR nodes (constants fold at once);
// everything else is a shared, immutable payload.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "compiler/scene/scene.hpp"
#include "lang/ast.hpp"

namespace sdfc {

enum class VT : uint8_t { None, Number, Bool, Vector, List, Range, String, Material, Shape, Function, Modifier };
const char* type_name(VT t);

struct Env;
struct Value;
enum class Builtin : uint16_t;

struct Callable {
    std::string name;
    bool builtin = false;
    Builtin id{};
    const ast::Stmt* def = nullptr;  // user function
    Env* env = nullptr;              // its defining scope (kept alive by the interpreter)
};

struct BoundArgs;
// A modifier waiting for its target: `translate([1, 0, 0])`, `union`, `material(gold)`.
struct ModifierVal {
    Builtin id{};
    std::string name;
    Loc loc;
    std::shared_ptr<const BoundArgs> args;
    MaterialN material{};  // for material()/color()
    ColorFn color_at;      // color(field (p) -> [r, g, b]): the colour at each point
};

struct RangeVal {
    float start = 0, step = 1, end = 0;
    // The elements [start : step : end] holds (what `for` iterates). The ends and the step
    // are floats: the slack covers their rounding (a few float ulps of each), so that
    // [0 : 0.1 : 10] ends at 10 although 0.1f is a little over a tenth.
    double count() const {
        const double q = (double(end) - start) / step;
        const double slack = 4.0 * 0x1p-24 * ((std::fabs(double(start)) + std::fabs(double(end))) / std::fabs(double(step)) + std::fabs(q)) + 1e-9;
        return std::max(0.0, std::floor(q + slack) + 1);
    }
};

struct Value {
    VT t = VT::None;
    uint8_t n = 0;                 // components of Number (1), Bool (1), Vector (2-4)
    uint32_t depth = 0;            // List: lists nested inside, plus one (bounded by max_nesting)
    std::array<NodeId, 4> c{};
    RangeVal range;
    std::shared_ptr<const std::vector<Value>> list;
    std::shared_ptr<const std::string> str;
    std::shared_ptr<const MaterialN> mat;
    ShapePtr shape;
    std::shared_ptr<const Callable> fn;
    std::shared_ptr<const ModifierVal> mod;

    static Value number(NodeId v) { Value x; x.t = VT::Number; x.n = 1; x.c[0] = v; return x; }
    static Value boolean(NodeId v) { Value x; x.t = VT::Bool; x.n = 1; x.c[0] = v; return x; }
    static Value vector(const NodeId* v, int n) {
        Value x; x.t = VT::Vector; x.n = static_cast<uint8_t>(n);
        for (int i = 0; i < n; ++i) x.c[i] = v[i];
        return x;
    }
    static Value of_shape(ShapePtr s) { Value x; x.t = VT::Shape; x.shape = std::move(s); return x; }
    bool numeric() const { return t == VT::Number || t == VT::Vector || t == VT::Bool; }
};

// Arguments bound to a builtin's parameters (null where not given).
struct BoundArgs {
    std::vector<std::unique_ptr<Value>> values;
    std::vector<Loc> locs;
    Loc call_loc;
    const Value* get(size_t i) const { return i < values.size() ? values[i].get() : nullptr; }
};

}  // namespace sdfc
