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
        {"intersection_for", "write `intersection { for (i = [0 : 2]) ... }`: a loop alone in an intersection gives its iterations"},
        {"union_for", "a `for` in a block unions its shapes: `union { for (i = [0 : 2]) ... }`"},
        {"echo", "sdfc has no echo: `sdfc eval SCENE --at X,Y,Z` prints distances"},
        {"include", "sdfc reads another file with `import \"file.sdf\";` (its defs and lets)"},
        {"use", "sdfc reads another file with `import \"file.sdf\";` (its defs and lets)"},
        {"each", "sdfc has no each: a list comprehension's `for` adds one element per item, `[for (x = list) x]`"},
        {"hull", "sdfc has no hull(): for two spheres, capsule(a, b, r) or cone(h, r1, r2); smooth_union(k) with a large k "
                 "approximates others"},
        {"minkowski", "minkowski() with a sphere is sdfc's `round(r) shape`: the shape grown by r, its edges rounded"},
        {"offset", "offset(r) of a profile is sdfc's `round(r) profile`; round(-r) shrinks it"},
        {"linear_extrude", "sdfc's is `extrude(h) profile`, centred on z = 0 (OpenSCAD's starts at z = 0)"},
        {"rotate_extrude", "sdfc's is `revolve(offset) profile`, about the y axis"},
        {"str", "sdfc has no string functions: strings name colours and settings"},
        {"assert", "sdfc has no assert: a shape's arguments are checked where they are given"},
        {"undef", "sdfc has no undef: give a default value"},
        {"text", "sdfc has no text(): shapes are distance functions, and fonts are not"},
        {"polyhedron", "sdfc has no polyhedron(): build the solid from primitives, or extrude(h) polygon(points) for a prism"},
        {"resize", "sdfc has no resize(): scale([sx, sy, sz]) by the ratio of the sizes"},
        {"break", "sdfc has no break: loops unroll; guard the body instead, `if (going) { ... }`"},
        {"continue", "sdfc has no continue: loops unroll; guard the body instead, `if (keep) { ... }`"},
        {"iResolution", "a scene has no screen: `render(width, height)` or --width/--height; a field takes the point p"},
        {"fragCoord", "a scene has no screen: a field takes the point p, `field (p) -> length(p) - 1`"},
        {"iMouse", "no mouse in a scene: a `param(...)` gives the html page a slider"},
        {"uniform", "a value the page turns is `let NAME = param(value, min, max);`"},
        {"void", "sdfc has no types: a scene is shapes, `field (p) -> ...` for a custom distance"},
        {"const", "sdfc has no types: `let a = 1.5;` (a let is constant)"},
    };
    for (const Habit& h : kHabits)
        if (h.name == name) return " (" + std::string(h.hint) + ")";
    return "";
}

// What OpenSCAD's argument `param` of `shape` is in sdfc, or "". With `param` empty: a hint
// (" (...)") for more positional arguments than sdfc's form takes.
inline std::string openscad_argument_hint(std::string_view shape, std::string_view param) {
    const bool round = shape == "sphere" || shape == "circle" || shape == "cylinder";
    if (param.empty())
        return shape == "cylinder" ? " (OpenSCAD's cylinder(h, r1, r2) is sdfc's cone(h, r1, r2))" : "";
    if (shape == "cylinder" && (param == "r1" || param == "r2" || param == "d1" || param == "d2"))
        return "a cylinder with two radii is a cone, cone(h, r1, r2) (OpenSCAD's d1, d2 are twice those)";
    if (round && param == "d") return "give the radius, r = d / 2";
    if (param == "center") {
        if (shape == "cylinder") return "it is always centred on the origin, along y";
        if (shape == "box" || shape == "square" || shape == "sphere" || shape == "circle" || shape == "round_box" || shape == "cone" ||
            shape == "hex_prism" || shape == "tri_prism")
            return "sdfc's shapes are centred on the origin (OpenSCAD's center = true); translate one to move it";
    }
    if (shape == "rotate" && (param == "a" || param == "v"))
        return "sdfc's forms are rotate([x, y, z]) (degrees about x, then y, then z), rotate(angle, axis) and rotate(y = angle)";
    if (shape == "translate" && param == "v") return "give the vector alone, translate([x, y, z])";
    if (shape == "extrude" && param == "height") return "the height is h, extrude(h = 2) (OpenSCAD's linear_extrude(height = 2))";
    return "";
}

}  // namespace sdfc
