// Hints for what users of OpenSCAD and GLSL write by habit: a name sdfc does not have, or a
// statement it does not parse, gets the sdfc way instead of a bare "unknown name" or
// "expected ';'" (issue 16).
#pragma once
#include <string>
#include <string_view>

namespace sdfc {

// " (...)" for a name another language uses where sdfc has another form, or "".
inline std::string habit_hint(std::string_view name) {
    struct Habit {
        std::string_view name, hint;
    };
    static constexpr Habit kHabits[] = {
        {"cube", "sdfc's is `box(size)`, centred on the origin"},
        {"module", "sdfc defines shapes and functions alike with `def NAME(PARAMS) = ...;`"},
        {"function", "sdfc defines functions with `def NAME(PARAMS) = ...;`"},
        {"children", "sdfc has no children(): pass the shape as a parameter, `def at(v, s) = translate(v) s;`"},
        {"vec2", "vectors are written in brackets: `[x, y]`"},
        {"vec3", "vectors are written in brackets: `[x, y, z]`"},
        {"vec4", "vectors are written in brackets: `[x, y, z, w]`"},
        {"float", "sdfc has no types: `let a = 1.5;`"},
        {"int", "sdfc has no types: `let n = 3;`"},
        {"return", "a def's value is its expression, `def f(x) = x * 2;`, or the last expression of its { } block"},
        {"intersection_for", "write `intersection { for (i = [0 : 2]) ... }`"},
        {"union_for", "a `for` in a block unions its shapes: `union { for (i = [0 : 2]) ... }`"},
        {"echo", "sdfc has no echo: `sdfc eval SCENE --at X,Y,Z` prints distances"},
    };
    for (const Habit& h : kHabits)
        if (h.name == name) return " (" + std::string(h.hint) + ")";
    return "";
}

}  // namespace sdfc
