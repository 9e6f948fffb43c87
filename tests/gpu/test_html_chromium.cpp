// The `--target html` page in a real browser: headless Chromium (Debian's `chromium`, WebGL2
// through ANGLE + SwiftShader, on the CPU) opens `page.html#capture=WxH`, which draws the
// script's camera at time 0 progressively (a quick low-resolution picture of one sample,
// then every sample of the full one in bands) before the page counts as loaded, and says on
// the console when each was done. For every example: the first picture within 15 s of the
// page's start, and the screenshot (the refined picture) within PSNR 40 dB of the CPU render
// at the script's samples. And a param's slider changes the picture with no new program.
// Skipped with a warning where no Chromium is installed (`apt-get install chromium`);
// SDFC_CHROMIUM names another binary.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <unistd.h>

#include "gpu_common.hpp"

namespace {

using namespace sdfc;
using namespace sdfc::gpu_test;

constexpr int kWidth = 240, kHeight = 135;
constexpr double kMinPsnr = 40.0, kFirstPictureMs = 15000.0;

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

// What one page load printed and showed.
struct PageRun {
    std::string log;                 // Chromium's stderr (the page's console lines among it)
    Rgb8 shot;                       // the finished picture
    std::vector<double> first_ms;    // "first picture at N ms", each run of the page
    std::vector<double> refined_ms;  // "refined picture at N ms"
    std::vector<int> linked;         // programs linked by then
    std::vector<std::string> centre; // the centre pixel "r,g,b"
};

std::string base64_decode(const std::string& in) {
    std::string out;
    uint32_t acc = 0;
    int bits = 0;
    for (char c : in) {
        int v = c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52 : c == '+' ? 62 : c == '/' ? 63 : -1;
        if (v < 0) continue;
        acc = acc << 6 | uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out += static_cast<char>((acc >> bits) & 255u);
        }
    }
    return out;
}

// Chromium on `page`#capture=WxH`extra` (software WebGL2: ANGLE's SwiftShader backend);
// the console goes to stderr (--enable-logging=stderr), the finished picture with it as a
// data: address (the page's own read-back; a headless --screenshot may come too early).
PageRun run_page(const std::string& bin, const fs::path& page, const fs::path& dir, const std::string& extra = "") {
    PageRun r;
    const fs::path shot = dir / "page.png", log = dir / "chromium.log", profile = dir / "profile";
    std::error_code ec;
    fs::remove(shot, ec);
    fs::remove_all(profile, ec);
    const std::string url = "file://" + fs::absolute(page).string() + "#capture=" + std::to_string(kWidth) + "x" + std::to_string(kHeight) + extra;
    const std::string cmd = "timeout 900 " + quote(bin) +
                            " --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader"
                            " --disable-background-networking --disable-gpu-sandbox --no-first-run --hide-scrollbars"
                            " --enable-logging=stderr --v=0 --user-data-dir=" +
                            quote(profile.string()) + " --window-size=" + std::to_string(kWidth) + "," + std::to_string(kHeight) +
                            " --dump-dom " + quote(url) + " > /dev/null 2> " + quote(log.string());
    std::printf("running: %s\n", cmd.c_str());
    std::fflush(stdout);
    std::system(cmd.c_str());
    r.log = read_text(log);
    std::string lines;  // the page's lines but its picture, for the regexes below
    {
        std::stringstream in(r.log);
        std::string line;
        while (std::getline(in, line))
            if (line.find("sdfc preview") != std::string::npos && line.find("sdfc preview: picture") == std::string::npos) lines += line + "\n";
    }
    static const std::regex first(R"(first picture at (\d+) ms)"), refined(R"(refined picture at (\d+) ms \([^,]*, [^,]*, (\d+) program linked, centre pixel (\d+,\d+,\d+)\))");
    for (auto it = std::sregex_iterator(lines.begin(), lines.end(), first); it != std::sregex_iterator(); ++it)
        r.first_ms.push_back(std::stod((*it)[1]));
    for (auto it = std::sregex_iterator(lines.begin(), lines.end(), refined); it != std::sregex_iterator(); ++it) {
        r.refined_ms.push_back(std::stod((*it)[1]));
        r.linked.push_back(std::stoi((*it)[2]));
        r.centre.push_back((*it)[3]);
    }
    // (Not std::regex over the picture's 40 KB: it recurses per character.)
    static const std::string kPicture = "sdfc preview: picture data:image/png;base64,";
    std::string png;
    for (size_t at = r.log.find(kPicture); at != std::string::npos; at = r.log.find(kPicture, at + 1)) {
        const size_t b = at + kPicture.size(), e = r.log.find_first_not_of(
            "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/=", b);
        png = base64_decode(r.log.substr(b, (e == std::string::npos ? r.log.size() : e) - b));
    }
    if (!png.empty()) std::ofstream(shot, std::ios::binary) << png;
    if (!png.empty() && fs::exists(shot)) {
        Rgb8 got = to_rgb8(read_image(shot.string()));
        if (got.width >= kWidth && got.height >= kHeight) {  // a larger viewport: the canvas is at the top left
            r.shot = Rgb8{kWidth, kHeight, std::vector<uint8_t>(static_cast<size_t>(kWidth) * kHeight * 3)};
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth * 3; ++x)
                    r.shot.px[static_cast<size_t>(y) * kWidth * 3 + x] = got.px[static_cast<size_t>(y) * got.width * 3 + x];
        }
    }
    return r;
}

// The page's console lines and Chromium's errors, each cut to 300 characters.
std::string summary(const std::string& log) {
    std::stringstream in(log);
    std::string line, out;
    while (std::getline(in, line))
        if (line.find("sdfc preview") != std::string::npos || line.find("ERROR") != std::string::npos || line.find("Uncaught") != std::string::npos)
            if (line.find("dbus") == std::string::npos) out += line.substr(0, 300) + "\n";
    return out;
}

fs::path page_of(const std::string& scene, const fs::path& dir, const std::vector<Define>& defines = {}) {
    SourceManager sm;
    InterpretOptions o;
    o.time = std::nullopt;
    o.defines = defines;
    Scene s = load_scene(sm, scene, o);
    const fs::path page = dir / "page.html";
    std::ofstream(page, std::ios::binary) << emit_glsl(s, GlslTarget::Html);
    return page;
}

// The CPU picture the page should show: the script's settings (samples included) at W x H.
Rgb8 cpu_of(const std::string& scene, const std::vector<Define>& defines = {}) {
    SourceManager sm;
    InterpretOptions o;
    o.defines = defines;
    Scene s = load_scene(sm, scene, o);
    CompiledScene cs = compile_scene(s);
    cs.render.width = kWidth;
    cs.render.height = kHeight;
    return to_rgb8(render(cs, RenderOptions{}));
}

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = out_dir() / "html" / name;
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::create_directories(dir);
    return dir;
}

}  // namespace

TEST_CASE("every example's html page draws a first picture within 15 s, then the CPU's picture, in headless Chromium",
          "[gpu][html][chromium]") {
    const std::string bin = find_chromium();
    if (bin.empty()) {
        WARN("SKIPPED: no chromium on PATH (apt-get install chromium), so the WebGL2 page is not checked");
        return;
    }
    std::vector<std::string> files = examples();
    if (const char* e = std::getenv("SDFC_HTML_EXAMPLE"); e && *e) files = {e};  // one scene (development)
    REQUIRE_FALSE(files.empty());
    for (const std::string& scene : files) {
        const std::string name = fs::path(scene).stem().string();
        INFO("example " << scene << ", chromium " << bin);
        const fs::path dir = fresh_dir(name);
        const PageRun r = run_page(bin, page_of(scene, dir), dir);
        INFO("log:\n" << summary(r.log));
        REQUIRE(r.first_ms.size() == 1);
        REQUIRE(r.refined_ms.size() == 1);
        REQUIRE(r.shot.width == kWidth);
        const Rgb8 cpu = cpu_of(scene);
        save(cpu, dir / "cpu.png");
        const double p = psnr(cpu, r.shot);
        std::printf("%-14s first picture at %6.0f ms, refined at %6.0f ms; PSNR against the CPU %.2f dB (%s)\n", name.c_str(), r.first_ms[0],
                    r.refined_ms[0], p, dir.c_str());
        std::fflush(stdout);
        CHECK(r.first_ms[0] <= kFirstPictureMs);
        CHECK(p >= kMinPsnr);
    }
}

TEST_CASE("a param's slider redraws the html page without a new program, as -D renders it", "[gpu][html][chromium]") {
    const std::string bin = find_chromium();
    if (bin.empty()) {
        WARN("SKIPPED: no chromium on PATH");
        return;
    }
    const std::string scene = (fs::path(SDFC_SOURCE_DIR) / "tests" / "gpu" / "scenes" / "params.sdf").string();
    const fs::path dir = fresh_dir("params");
    const PageRun r = run_page(bin, page_of(scene, dir), dir, "&param=size:1.3&param=lift:0.6");
    INFO("log:\n" << summary(r.log));
    REQUIRE(r.refined_ms.size() == 3);  // the script's values, then after each slider
    CHECK(r.linked == std::vector<int>{1, 1, 1});
    CHECK(r.centre[0] != r.centre[1]);
    CHECK(r.centre[1] != r.centre[2]);
    const Rgb8 cpu = cpu_of(scene, {{"size", "1.3"}, {"lift", "0.6"}});
    save(cpu, dir / "cpu.png");
    const double p = psnr(cpu, r.shot);
    std::printf("params: centre pixel %s -> %s -> %s; PSNR against sdfc render -D size=1.3 -D lift=0.6: %.2f dB\n", r.centre[0].c_str(),
                r.centre[1].c_str(), r.centre[2].c_str(), p);
    CHECK(p >= kMinPsnr);
}
