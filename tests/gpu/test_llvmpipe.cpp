// The GLSL backend against the CPU renderer: every example's Shadertoy-target shader, inside
// a Shadertoy-like wrapper, drawn by Mesa's llvmpipe through headless EGL (surfaceless
// platform, GLES 3.0 context, an FBO, glReadPixels), must match `sdfc render --samples 1` at
// the same size with PSNR >= 40 dB. Without a usable EGL/llvmpipe the test is skipped with a
// warning (CI installs libegl-dev libgles-dev libgl1-mesa-dri).
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "shadertoy.hpp"

namespace {

using namespace sdfc;
using namespace sdfc::gpu_test;

constexpr int kWidth = 160, kHeight = 90;
constexpr double kMinPsnr = 45.0;

}  // namespace

TEST_CASE("every example drawn by llvmpipe from the Shadertoy GLSL matches the CPU renderer", "[gpu][llvmpipe]") {
    Gles gles;
    const std::string why = gles.init();
    if (!why.empty()) {
        WARN("SKIPPED: no headless GLES 3 through EGL/llvmpipe here: " << why);
        return;
    }
    std::printf("GL_RENDERER: %s\n", gles.renderer().c_str());
    if (gles.renderer().find("llvmpipe") == std::string::npos)
        WARN("the GLES renderer is '" << gles.renderer() << "', not llvmpipe");
    const auto files = examples();
    REQUIRE_FALSE(files.empty());
    double lowest = INFINITY;
    std::string lowest_name;
    const fs::path out = out_dir();
    for (const std::string& path : files) {
        const std::string name = fs::path(path).stem().string();
        INFO("example " << path);
        auto t0 = std::chrono::steady_clock::now();
        const Rgb8 cpu = cpu_render(path, kWidth, kHeight);
        auto t1 = std::chrono::steady_clock::now();
        Rgb8 gpu;
        const std::string err = draw_shadertoy(gles, shadertoy_wrap(glsl_of(path, GlslTarget::Shadertoy)), kWidth, kHeight, gpu);
        auto t2 = std::chrono::steady_clock::now();
        REQUIRE(err == "");
        const double p = psnr(cpu, gpu);
        std::printf("  %-28s PSNR %7.2f dB   (cpu %5.0f ms, llvmpipe %6.0f ms)\n", name.c_str(), p,
                    std::chrono::duration<double, std::milli>(t1 - t0).count(), std::chrono::duration<double, std::milli>(t2 - t1).count());
        std::fflush(stdout);
        if (p < lowest) lowest = p, lowest_name = name;
        if (p < kMinPsnr || std::getenv("SDFC_GPU_OUT")) {
            save(cpu, out / (name + ".cpu.png"));
            save(gpu, out / (name + ".llvmpipe.png"));
        }
        CHECK(p >= kMinPsnr);
    }
    std::printf("lowest PSNR: %.2f dB (%s) over %zu examples at %dx%d\n", lowest, lowest_name.c_str(), files.size(), kWidth, kHeight);
}
