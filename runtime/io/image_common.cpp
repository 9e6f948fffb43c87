// What images need without OpenImageIO: the sRGB encoding, the heat map, side-file names.
// Built into sdfc_io and into the image module (runtime/io/oiio) alike.
#include <cctype>
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "compiler/render/rules.h"
#include "runtime/io/image.hpp"

namespace sdfc {

namespace fs = std::filesystem;

float linear_to_srgb(float v) { return rules::sdf_to_srgb(v); }  // the shader's encoding too

float srgb_to_linear(float v) {
    if (!(v > 0.0f)) return 0.0f;
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

void heat_color(float t, float rgb[3]) {
    // Piecewise-linear ramp through five stops (display values).
    static constexpr float stops[5][3] = {
        {0.02f, 0.02f, 0.15f}, {0.25f, 0.10f, 0.65f}, {0.85f, 0.20f, 0.45f}, {1.00f, 0.60f, 0.10f}, {1.00f, 1.00f, 0.75f}};
    if (!(t > 0.0f)) t = 0.0f;
    if (t > 1.0f) t = 1.0f;
    float s = t * 4.0f;
    int i = std::min(static_cast<int>(s), 3);
    float f = s - static_cast<float>(i);
    for (int c = 0; c < 3; ++c) rgb[c] = stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f;
}


std::string aov_side_path(const std::string& path, const std::string& aov) {
    fs::path p(path);
    std::string ext = p.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    const bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".pfm";  // float pictures: float planes
    return (p.parent_path() / (p.stem().string() + "." + aov + (is_float ? ".exr" : ".png"))).string();
}

}  // namespace sdfc
