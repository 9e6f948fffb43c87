// Colour names: color("tomato"), and a CSS name or #rrggbb wherever a parameter takes a
// colour (material's, light's, ambient's, background's color).
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "compiler/base/names.hpp"
#include "lang/css_colors.hpp"
#include "lang/interp.hpp"

namespace sdfc {

Value Interp::colour_name(const std::string& name, Loc loc) {
    const auto rgb = css_color(name);
    if (!rgb) {
        std::vector<std::string> names;
        for (const CssColor& k : kCssColors) names.push_back(k.name);
        const std::string near = nearest_name(name, names);
        fail(loc, near.empty() ? fmt::format("unknown colour {:?} (a CSS name such as \"tomato\", or \"#rrggbb\")", name)
                               : fmt::format("unknown colour {:?} (did you mean \"{}\"?)", name, near));
    }
    // "#rgba" and "#rrggbbaa" (CSS's): the alpha is not a colour's, as color([r, g, b, a])'s.
    if (name.size() == 5 || name.size() == 9) {
        const std::string_view a = std::string_view(name).substr(name.size() == 5 ? 4 : 7);
        if (name[0] == '#' && a.find_first_not_of("fF") != std::string_view::npos)
            warn(loc, "the colour's alpha is ignored: for see-through, material(transparency = ...)");
    }
    // sRGB bytes, made linear like every colour of a scene.
    NodeId c[3];
    for (int k = 0; k < 3; ++k) {
        const float v = float((*rgb >> (16 - 8 * k)) & 0xFF) / 255.0f;
        c[k] = g->constant(v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f));
    }
    return Value::vector(c, 3);
}

}  // namespace sdfc
