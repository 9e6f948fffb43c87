// The `--target html` page in a real browser: headless Chromium (Debian's `chromium`, WebGL2
// through ANGLE + SwiftShader) opens `page.html#capture=WxH`, which draws one frame at the
// script's camera and time 0 on a W x H canvas; the screenshot must match the CPU render of the
// same scene at the same size within PSNR 30 dB. Skipped with a warning where no Chromium is
// installed (`apt-get install chromium`); SDFC_CHROMIUM names another binary.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unistd.h>
#include <string>

#include "gpu_common.hpp"

namespace {

using namespace sdfc;
using namespace sdfc::gpu_test;

constexpr int kWidth = 320, kHeight = 180;
constexpr double kMinPsnr = 30.0;

std::string find_chromium() {
    if (const char* e = std::getenv("SDFC_CHROMIUM"); e && *e) return e;
    const char* path = std::getenv("PATH");
    std::stringstream ss(path ? path : "/usr/bin:/bin");
    std::string dir;
    while (std::getline(ss, dir, ':'))
        for (const char* name : {"chromium", "chromium-browser", "google-chrome", "google-chrome-stable"}) {
            fs::path p = fs::path(dir.empty() ? "." : dir) / name;
            std::error_code ec;
            if (fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0) return p.string();
        }
    return "";
}

std::string quote(const std::string& s) {
    std::string o = "'";
    for (char c : s) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return o + "'";
}

std::string read_text(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// The flags the brief of issue 4 names: software WebGL2 through ANGLE's SwiftShader backend.
std::string chromium_command(const std::string& bin, const fs::path& profile, const std::string& extra, const std::string& url) {
    return "timeout 600 " + quote(bin) +
           " --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader"
           " --disable-background-networking --disable-gpu-sandbox --no-first-run --hide-scrollbars"
           " --user-data-dir=" +
           quote(profile.string()) + " --window-size=" + std::to_string(kWidth) + "," + std::to_string(kHeight) + " " + extra + " " +
           quote(url);
}

std::string pick_example() {
    if (const char* e = std::getenv("SDFC_HTML_EXAMPLE"); e && *e) return e;  // another scene (development)
    const auto files = examples();
    for (const std::string& f : files)
        if (fs::path(f).filename() == "three-tori.sdf") return f;
    for (const std::string& f : files)
        if (fs::path(f).extension() == ".sdf") return f;
    return "";
}

}  // namespace

TEST_CASE("the html page draws the scene in headless Chromium (WebGL2) like the CPU renderer", "[gpu][html][chromium]") {
    const std::string bin = find_chromium();
    if (bin.empty()) {
        WARN("SKIPPED: no chromium on PATH (apt-get install chromium), so the WebGL2 page is not checked");
        return;
    }
    const std::string example = pick_example();
    REQUIRE(example != "");
    INFO("example " << example << ", chromium " << bin);
    const fs::path dir = out_dir() / "html";
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::create_directories(dir);
    const fs::path page = dir / "page.html", shot = dir / "screenshot.png", log = dir / "chromium.log";
    {
        SourceManager sm;
        InterpretOptions o;
        o.time = std::nullopt;
        Scene s = load_scene(sm, example, o);
        std::ofstream(page, std::ios::binary) << emit_glsl(s, GlslTarget::Html);
    }
    // The CPU picture the page should show: the script's settings (samples included) at W x H.
    Rgb8 cpu;
    {
        SourceManager sm;
        Scene s = load_scene(sm, example, InterpretOptions{});
        CompiledScene cs = compile_scene(s);
        cs.render.width = kWidth;
        cs.render.height = kHeight;
        cpu = to_rgb8(render(cs, RenderOptions{}));
    }
    save(cpu, dir / "cpu.png");

    const std::string url = "file://" + fs::absolute(page).string() + "#capture=" + std::to_string(kWidth) + "x" + std::to_string(kHeight);
    const std::string cmd = chromium_command(bin, dir / "profile", "--screenshot=" + quote(shot.string()), url) + " > " +
                            quote(log.string()) + " 2>&1";
    std::printf("running: %s\n", cmd.c_str());
    const int rc = std::system(cmd.c_str());
    INFO("command: " << cmd << "\nexit status " << rc << "\nlog:\n" << read_text(log));
    REQUIRE(fs::exists(shot));
    Image img = read_image(shot.string());
    Rgb8 got = to_rgb8(img);
    REQUIRE(got.width >= kWidth);
    REQUIRE(got.height >= kHeight);
    if (got.width != kWidth || got.height != kHeight) {  // a larger viewport: the canvas is at the top left
        Rgb8 crop{kWidth, kHeight, std::vector<uint8_t>(static_cast<size_t>(kWidth) * kHeight * 3)};
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth * 3; ++x) crop.px[static_cast<size_t>(y) * kWidth * 3 + x] = got.px[static_cast<size_t>(y) * got.width * 3 + x];
        got = crop;
    }
    const double p = psnr(cpu, got);
    std::printf("chromium WebGL2 page vs CPU render (%s, %dx%d): PSNR %.2f dB; pictures in %s\n", fs::path(example).filename().c_str(), kWidth,
                kHeight, p, dir.c_str());
    if (p < kMinPsnr) {
        // Say why: the page's title and message tell whether WebGL2 was there at all.
        const fs::path dom = dir / "dom.html";
        std::system((chromium_command(bin, dir / "profile", "--dump-dom", url) + " > " + quote(dom.string()) + " 2>/dev/null").c_str());
        const std::string d = read_text(dom);
        const size_t t0 = d.find("<title>"), t1 = d.find("</title>");
        const size_t m0 = d.find("id=\"message\"");
        UNSCOPED_INFO("page title: " << (t0 != std::string::npos && t1 > t0 ? d.substr(t0 + 7, t1 - t0 - 7) : "?"));
        UNSCOPED_INFO("page message: " << (m0 != std::string::npos ? d.substr(m0, std::min<size_t>(600, d.size() - m0)) : "?"));
    }
    CHECK(p >= kMinPsnr);
}
