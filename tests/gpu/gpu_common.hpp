// Shared by the GPU tests: the examples, the CPU reference picture, 8-bit sRGB images and PSNR.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "compiler/bytecode/compile.hpp"
#include "compiler/glsl/glsl.hpp"
#include "lang/load.hpp"
#include "runtime/io/image.hpp"
#include "runtime/cpu/tracer.hpp"

namespace sdfc::gpu_test {

namespace fs = std::filesystem;

// 8-bit sRGB RGB pixels, row 0 at the top.
struct Rgb8 {
    int width = 0, height = 0;
    std::vector<uint8_t> px;  // width * height * 3
};

inline std::vector<std::string> examples() {
    std::vector<std::string> out;
    const char* env = std::getenv("SDFC_GPU_EXAMPLES");  // another folder of scenes (development)
    const fs::path dir = env && *env ? fs::path(env) : fs::path(SDFC_SOURCE_DIR) / "examples";
    if (!fs::is_directory(dir)) return out;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.is_regular_file() && (e.path().extension() == ".sdf" || e.path().extension() == ".vm")) out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

inline uint8_t to_u8(float display) {  // as runtime/io/image.cpp writes 8-bit files
    if (!(display > 0.0f)) return 0;
    if (display >= 1.0f) return 255;
    return static_cast<uint8_t>(display * 255.0f + 0.5f);
}

inline Rgb8 to_rgb8(const Image& img) {
    Rgb8 o{img.width, img.height, std::vector<uint8_t>(static_cast<size_t>(img.width) * img.height * 3)};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                o.px[(static_cast<size_t>(y) * img.width + x) * 3 + c] = to_u8(linear_to_srgb(img.at(x, y, std::min(c, img.channels - 1))));
    return o;
}

inline Image from_rgb8(const Rgb8& r) {
    Image img(r.width, r.height, 3);
    for (size_t i = 0; i < r.px.size(); ++i) img.pixels[i] = srgb_to_linear(r.px[i] / 255.0f);
    return img;
}

// `sdfc render --samples 1` at width x height, time 0.
inline Rgb8 cpu_render(const std::string& path, int width, int height) {
    SourceManager sm;
    Scene s = load_scene(sm, path, InterpretOptions{});
    CompiledScene cs = compile_scene(s);
    cs.render.width = width;
    cs.render.height = height;
    cs.render.samples = 1;
    return to_rgb8(render(cs, RenderOptions{}));
}

// The GLSL of `path` for `target`, with one sample per pixel (as the CPU reference).
inline std::string glsl_of(const std::string& path, GlslTarget target, bool one_sample = true) {
    SourceManager sm;
    InterpretOptions o;
    o.time = std::nullopt;
    Scene s = load_scene(sm, path, o);
    if (one_sample) s.render.samples = 1;
    return emit_glsl(s, target);
}

// PSNR over all RGB values (inf when identical).
inline double psnr(const Rgb8& a, const Rgb8& b) {
    if (a.width != b.width || a.height != b.height || a.px.size() != b.px.size() || a.px.empty()) return -1.0;
    double se = 0.0;
    for (size_t i = 0; i < a.px.size(); ++i) {
        const double d = static_cast<double>(a.px[i]) - static_cast<double>(b.px[i]);
        se += d * d;
    }
    if (se == 0.0) return INFINITY;
    return 10.0 * std::log10(255.0 * 255.0 / (se / static_cast<double>(a.px.size())));
}

// Where the tests leave pictures for a person to look at (SDFC_GPU_OUT, else a temp folder).
inline fs::path out_dir() {
    const char* e = std::getenv("SDFC_GPU_OUT");
    fs::path d = e && *e ? fs::path(e) : fs::temp_directory_path() / "sdfc-gpu-test";
    std::error_code ec;
    fs::create_directories(d, ec);
    return d;
}

inline void save(const Rgb8& r, const fs::path& p) {
    try {
        write_image(p.string(), from_rgb8(r), WriteOptions{false});
    } catch (...) {
    }
}

}  // namespace sdfc::gpu_test
