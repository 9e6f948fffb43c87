// The math built-ins (LANGUAGE.md section 3): each builds IR nodes, so a value may stay
// symbolic (a field's point, GLSL's time); constants fold and get their domain checks here
// (sqrt of a negative number, asin of 2, ...) with the argument's location.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "lang/interp.hpp"

namespace sdfc {

Value Interp::call_math(const BuiltinInfo& info, std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc) {
    Graph& gr = *g;
    using B = Builtin;
    if (info.id == B::Len) {  // (of any value with elements, not only numbers)
        if (args.size() != 1) fail(loc, fmt::format("len takes 1 argument, not {}", args.size()));
        const Value& a = args[0];
        size_t n = 0;
        if (a.t == VT::Vector) n = a.n;
        else if (a.t == VT::List) n = a.list->size();
        else if (a.t == VT::Range) n = size_t(a.range.count());
        else if (a.t == VT::String) n = size_t(std::count_if(a.str->begin(), a.str->end(), [](char c) { return (c & 0xC0) != 0x80; }));
        else fail(locs[0], fmt::format("len takes a list, a vector, a range or a string, not {}", describe(a)));
        return Value::number(gr.constant(float(n)));
    }
    if (info.id == B::Concat) {  // OpenSCAD's: lists and vectors give their elements, anything else itself
        size_t total = 0;  // (counted first: the copies are what costs)
        for (const Value& a : args) total += a.t == VT::Vector ? a.n : a.t == VT::List ? a.list->size() : 1;
        check_list_size(total, loc);
        std::vector<Value> items;
        for (const Value& a : args) {
            if (a.t == VT::Vector)
                for (int k = 0; k < a.n; ++k) items.push_back(Value::number(a.c[k]));
            else if (a.t == VT::List) items.insert(items.end(), a.list->begin(), a.list->end());
            else items.push_back(a);
        }
        return list_value(std::move(items), loc);
    }
    if (info.id == B::Lookup) return lookup(args, locs, loc);
    auto arity = [&](size_t lo, size_t hi) {
        if (args.size() < lo || args.size() > hi) {
            if (lo == hi) fail(loc, fmt::format("{} takes {} argument{}, not {}", info.name, lo, lo == 1 ? "" : "s", args.size()));
            fail(loc, fmt::format("{} takes {} to {} arguments, not {}", info.name, lo, hi, args.size()));
        }
        for (size_t i = 0; i < args.size(); ++i)
            if (!args[i].numeric())
                fail(locs[i], fmt::format("argument {} of {} must be a number or a vector, not {}", i + 1, info.name, describe(args[i])));
    };
    auto un = [&](Op op) {
        arity(1, 1);
        return componentwise(args[0], loc, [&](NodeId x) { return gr.unary(op, x); });
    };
    auto bin = [&](Op op) {
        arity(2, 2);
        return componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) { return gr.binary(op, x, y); });
    };
    auto need_vec = [&](size_t i) {
        if (args[i].t != VT::Vector) fail(locs[i], fmt::format("argument {} of {} must be a vector, not {}", i + 1, info.name, describe(args[i])));
    };
    auto dot = [&](const Value& a, const Value& b) {
        if (a.n != b.n) fail(loc, fmt::format("{} needs vectors of one size, not {} and {} components", info.name, a.n, b.n));
        NodeId s = gr.mul(a.c[0], b.c[0]);
        for (int i = 1; i < a.n; ++i) s = gr.add(s, gr.mul(a.c[i], b.c[i]));
        return s;
    };
    auto length = [&](const Value& a) {
        if (a.t == VT::Number) return gr.abs(a.c[0]);
        if (a.n == 2) return gr.binary(Op::Length2, a.c[0], a.c[1]);
        if (a.n == 3) return gr.ternary(Op::Length3, a.c[0], a.c[1], a.c[2]);
        return gr.sqrt(dot(a, a));
    };
    switch (info.id) {
        case B::Sin: return un(Op::Sin);
        case B::Cos: return un(Op::Cos);
        case B::Tan: return un(Op::Tan);
        case B::Asin:
        case B::Acos: {
            // Like sqrt(-1): a constant out of the domain is an error; in a field (p varies)
            // the argument is clamped to [-1, 1] (docs/language.md).
            arity(1, 1);
            for (int i = 0; i < args[0].n; ++i)
                if (gr.is_const(args[0].c[i]) && !(std::fabs(gr.const_value(args[0].c[i])) <= 1.0f))
                    fail(locs[0], fmt::format("{} of a number outside [-1, 1] ({})", info.name, gr.const_value(args[0].c[i])));
            return un(info.id == B::Asin ? Op::Asin : Op::Acos);
        }
        case B::Atan:
            if (args.size() == 2) return bin(Op::Atan2);  // GLSL's atan(y, x)
            arity(1, 2);
            return un(Op::Atan);
        case B::Atan2: return bin(Op::Atan2);
        case B::Sqrt: {
            arity(1, 1);
            for (int i = 0; i < args[0].n; ++i)
                if (gr.is_const(args[0].c[i]) && gr.const_value(args[0].c[i]) < 0) fail(locs[0], "sqrt of a negative number");
            return un(Op::Sqrt);
        }
        case B::Pow: {
            arity(2, 2);
            return componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) {
                if (gr.is_const(x) && gr.is_const(y)) {
                    const float a = gr.const_value(x), e = gr.const_value(y);
                    if (a < 0 && std::floor(e) != e)
                        fail(locs[0], fmt::format("pow of a negative number ({}) to a fractional power ({}) is not a real number", a, e));
                    if (a == 0 && e < 0) fail(locs[0], fmt::format("pow of zero to a negative power ({})", e));
                }
                return gr.binary(Op::Pow, x, y);
            });
        }
        case B::Exp: return un(Op::Exp);
        case B::Log: {
            arity(1, 1);
            for (int i = 0; i < args[0].n; ++i)
                if (gr.is_const(args[0].c[i]) && gr.const_value(args[0].c[i]) <= 0) fail(locs[0], "log of a number that is not positive");
            return un(Op::Log);
        }
        case B::Abs: return un(Op::Abs);
        case B::Sign: return un(Op::Sign);
        case B::Floor: return un(Op::Floor);
        case B::Ceil: return un(Op::Ceil);
        case B::Fract: return un(Op::Fract);
        case B::Mod: {
            arity(2, 2);
            return componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) {
                if (gr.is_const(y) && gr.const_value(y) == 0.0f) fail(locs[1], "mod by zero");
                return gr.binary(Op::Mod, x, y);
            });
        }
        case B::Min:
        case B::Max: {
            if (args.size() == 1 && args[0].t == VT::List) {  // OpenSCAD's max([x]), max of a long list
                const auto& items = *args[0].list;
                if (items.empty()) fail(locs[0], fmt::format("{} of an empty list", info.name));
                NodeId r = kNoNode;
                for (const Value& x : items) {
                    if (x.t != VT::Number) fail(locs[0], fmt::format("{} of a list takes numbers, not {}", info.name, describe(x)));
                    r = r == kNoNode ? x.c[0] : gr.binary(info.id == B::Min ? Op::Min : Op::Max, r, x.c[0]);
                }
                return Value::number(r);
            }
            if (args.size() == 1 && args[0].t == VT::Vector) {
                NodeId r = args[0].c[0];
                for (int i = 1; i < args[0].n; ++i) r = gr.binary(info.id == B::Min ? Op::Min : Op::Max, r, args[0].c[i]);
                return Value::number(r);
            }
            arity(2, 64);
            Value r = args[0];
            for (size_t i = 1; i < args.size(); ++i)
                r = componentwise2(r, args[i], loc, [&](NodeId x, NodeId y) { return gr.binary(info.id == B::Min ? Op::Min : Op::Max, x, y); });
            return r;
        }
        case B::Clamp: {
            arity(3, 3);
            Value lo = componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) { return gr.max(x, y); });
            return componentwise2(lo, args[2], loc, [&](NodeId x, NodeId y) { return gr.min(x, y); });
        }
        case B::Mix: {
            arity(3, 3);
            Value d = componentwise2(args[1], args[0], loc, [&](NodeId b, NodeId a) { return gr.sub(b, a); });
            Value t = componentwise2(d, args[2], loc, [&](NodeId x, NodeId k) { return gr.mul(x, k); });
            return componentwise2(args[0], t, loc, [&](NodeId a, NodeId x) { return gr.add(a, x); });
        }
        case B::Step: {
            arity(2, 2);
            // step(edge, x) = x < edge ? 0 : 1
            return componentwise2(args[0], args[1], loc, [&](NodeId edge, NodeId x) {
                return gr.sub(gr.constant(1), gr.binary(Op::Lt, x, edge));
            });
        }
        case B::Smoothstep: {
            arity(3, 3);
            Value w = componentwise2(args[1], args[0], loc, [&](NodeId b, NodeId a) { return gr.sub(b, a); });
            Value num_ = componentwise2(args[2], args[0], loc, [&](NodeId x, NodeId a) { return gr.sub(x, a); });
            Value t = componentwise2(num_, w, loc, [&](NodeId n, NodeId d) {
                if (gr.is_const(d) && gr.const_value(d) == 0.0f) fail(loc, "smoothstep with equal edges");
                return gr.clamp(gr.div(n, d), gr.constant(0), gr.constant(1));
            });
            return componentwise(t, loc, [&](NodeId x) {
                return gr.mul(gr.unary(Op::Square, x), gr.sub(gr.constant(3), gr.mul(gr.constant(2), x)));
            });
        }
        case B::Length:
        case B::Norm: arity(1, 1); return Value::number(length(args[0]));
        case B::Distance: {
            arity(2, 2);
            Value d = componentwise2(args[0], args[1], loc, [&](NodeId x, NodeId y) { return gr.sub(x, y); });
            return Value::number(length(d));
        }
        case B::Dot: arity(2, 2); need_vec(0); need_vec(1); return Value::number(dot(args[0], args[1]));
        case B::Cross: {
            arity(2, 2);
            need_vec(0);
            need_vec(1);
            const Value &a = args[0], &b = args[1];
            if (a.n != 3 || b.n != 3) fail(loc, "cross takes two 3-component vectors");
            NodeId c[3] = {gr.sub(gr.mul(a.c[1], b.c[2]), gr.mul(a.c[2], b.c[1])),
                           gr.sub(gr.mul(a.c[2], b.c[0]), gr.mul(a.c[0], b.c[2])),
                           gr.sub(gr.mul(a.c[0], b.c[1]), gr.mul(a.c[1], b.c[0]))};
            return Value::vector(c, 3);
        }
        case B::Normalize: {
            arity(1, 1);
            bool all_const = true, all_zero = true;
            for (int i = 0; i < args[0].n; ++i) {
                all_const &= gr.is_const(args[0].c[i]);
                all_zero &= gr.is_const(args[0].c[i]) && gr.const_value(args[0].c[i]) == 0.0f;
            }
            if (all_zero) fail(locs[0], "normalize of a zero vector");
            NodeId len = length(args[0]);
            const bool degenerate = gr.is_const(len) && !(gr.const_value(len) > 0.0f && std::isfinite(gr.const_value(len)));
            if (all_const && degenerate) {
                // In double: the float length of [1e-30, 0, 0] underflows to 0.
                double sq = 0;
                for (int i = 0; i < args[0].n; ++i) sq += double(gr.const_value(args[0].c[i])) * gr.const_value(args[0].c[i]);
                const double dl = std::sqrt(sq);
                NodeId c[4];
                for (int i = 0; i < args[0].n; ++i) c[i] = gr.constant(float(double(gr.const_value(args[0].c[i])) / dl));
                return args[0].t == VT::Number ? Value::number(c[0]) : Value::vector(c, args[0].n);
            }
            if (gr.is_const(len) && gr.const_value(len) == 0.0f) fail(locs[0], "normalize of a zero vector");
            return componentwise(args[0], loc, [&](NodeId x) { return gr.div(x, len); });
        }
        case B::Radians: arity(1, 1); return componentwise(args[0], loc, [&](NodeId x) { return gr.mulc(x, 3.14159265358979f / 180.0f); });
        case B::Degrees: arity(1, 1); return componentwise(args[0], loc, [&](NodeId x) { return gr.mulc(x, 180.0f / 3.14159265358979f); });
        case B::Param: return make_param(args, locs, loc);
        case B::Noise: {
            arity(1, 1);
            Vec3N p = vec3(args[0], locs[0], "the argument of noise", false);
            return Value::number(gr.ternary(Op::Noise3, p[0], p[1], p[2]));
        }
        default: break;
    }
    fail(loc, fmt::format("internal: {} is not a math function", info.name));
}

// let name = param(value, min = value - max(|value|, 1), max = value + max(|value|, 1), step):
// the value, or in GLSL a uniform the html page turns with a slider over [min, max].
constexpr size_t kMaxParams = 64;

Value Interp::make_param(std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc) {
    if (param_let.empty())
        fail(loc, "param(...) gives a top-level let its value, which the html page's slider turns: let size = param(1, 0.1, 3);");
    if (++params_in_let > 1) fail(loc, fmt::format("'{}' has a param(...) already: one a let, each its own slider", param_let));
    if (args.empty() || args.size() > 4) fail(loc, fmt::format("param takes 1 to 4 arguments (value, min, max, step), not {}", args.size()));
    static const char* const kWhat[] = {"the param's value", "the param's min", "the param's max", "the param's step"};
    float v[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i].t != VT::Number) fail(locs[i], fmt::format("{} must be a number, not {}", kWhat[i], describe(args[i])));
        v[i] = const_num(args[i], locs[i], kWhat[i]);
        if (!std::isfinite(v[i])) fail(locs[i], fmt::format("{} is not a finite number", kWhat[i]));
    }
    float value = v[0];
    const float span = std::max(std::fabs(value), 1.0f);
    float lo = args.size() > 1 ? v[1] : value - span, hi = args.size() > 2 ? v[2] : value + span;
    if (!(lo < hi)) fail(args.size() > 2 ? locs[2] : loc, fmt::format("the param's max ({}) must be above its min ({})", hi, lo));
    if (value < lo || value > hi) fail(locs[0], fmt::format("the param's value {} is outside [{}, {}]", value, lo, hi));
    if (param_start) {  // glsl -D NAME=VALUE: the slider starts there, its range grown to hold it
        value = *param_start;
        lo = std::min(lo, value);
        hi = std::max(hi, value);
    }
    // By default the power of ten at most a thousandth of the range: whole numbers (and
    // tenths...) lie on the slider's grid, as a count or a `-D` value needs.
    const float step = args.size() > 3 ? v[3] : std::pow(10.0f, std::floor(std::log10((hi - lo) / 1000.0f)));
    if (!(step > 0.0f)) fail(locs[3], "the param's step must be above 0");
    if (opts.time || param_fixed) return Value::number(g->constant(value));  // the CPU (or -D's): a constant
    // Each is a uniform; WebGL2 promises 224 vectors for a fragment shader, the renderer's own included.
    if (scene.params.size() >= kMaxParams) fail(loc, fmt::format("a script has at most {} params", kMaxParams));
    const int index = static_cast<int>(scene.params.size());
    scene.params.push_back(SceneParam{param_let, value, lo, hi, step, loc});
    return Value::number(g->with_imm(Op::Param, kNoNode, kNoNode, static_cast<float>(index)));
}

// OpenSCAD's lookup(key, [[k0, v0], [k1, v1], ...]): v linear between the keys (in any
// order), the end values beyond them. The table is constant; the key may vary (a field's
// point): then a chain of selects.
Value Interp::lookup(std::vector<Value>& args, const std::vector<Loc>& locs, Loc loc) {
    Graph& gr = *g;
    if (args.size() != 2) fail(loc, fmt::format("lookup takes 2 arguments (a key and a table), not {}", args.size()));
    NodeId key = num(args[0], locs[0], "lookup's key");
    std::vector<std::pair<float, float>> rows;
    auto row = [&](const Value& r) {
        if (r.t == VT::List && r.list->size() == 2)  // [key, vector]: a pair, but not of numbers
            for (const Value& x : *r.list)
                if (x.t != VT::Number)
                    fail(locs[1], fmt::format("lookup's table holds [key, value] pairs of numbers; this pair holds {}", describe(x)));
        if (r.t != VT::Vector || r.n != 2 || !gr.is_const(r.c[0]) || !gr.is_const(r.c[1]))
            fail(locs[1], fmt::format("lookup's table holds [key, value] pairs of constants, not {}", describe(r)));
        rows.emplace_back(gr.const_value(r.c[0]), gr.const_value(r.c[1]));
    };
    const Value& t = args[1];
    if (t.t != VT::List) fail(locs[1], fmt::format("lookup's table is a list of [key, value] pairs, not {}", describe(t)));
    for (const Value& r : *t.list) row(r);
    if (rows.empty()) fail(locs[1], "lookup's table is empty");
    std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    NodeId r = gr.constant(rows.back().second);
    for (size_t i = rows.size() - 1; i-- > 0;) {
        const auto [k0, v0] = rows[i];
        const auto [k1, v1] = rows[i + 1];
        // (equal keys: the later row's value from that key on)
        NodeId u = k1 > k0 ? gr.clamp(gr.div(gr.sub(key, gr.constant(k0)), gr.constant(k1 - k0)), gr.constant(0.0f), gr.constant(1.0f))
                           : gr.constant(1.0f);
        NodeId seg = gr.add(gr.constant(v0), gr.mul(u, gr.constant(v1 - v0)));
        r = gr.select(gr.binary(Op::Lt, key, gr.constant(k1)), seg, r);
    }
    return Value::number(checked(r, loc));
}

}  // namespace sdfc
