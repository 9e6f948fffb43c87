// Compositing outputs (issue 20): alpha as the pixel's coverage with the background left
// out, the EXR channel layout (R G B A Z N.x N.y N.z steps.Y, misses at Z = +inf), straight
// colour in 8-bit files, float side files beside a float picture.
#include <catch2/catch.hpp>
#include "support.hpp"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>

#include "runtime/cpu/tracer.hpp"
#include "runtime/io/image.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {

const char* kScene =
    "camera(position = [0, 0, 5], target = [0, 0, 0]);\n"
    "background([0.2, 0.4, 0.6]);\n"
    "render(width = 48, height = 32, samples = 4);\n"
    "color([0.9, 0.2, 0.1]) sphere(1);\n";

fs::path dir_for(const std::string& name) {
    fs::path d = fs::temp_directory_path() / ("sdfc-alpha-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(d);  // (an earlier process with this pid may have left files)
    fs::create_directories(d);
    return d;
}

}  // namespace

TEST_CASE("alpha is the coverage, and the background is left out of the colour", "[render][alpha]") {
    auto c = test::compile_text(kScene);
    const Image plain = render(c->cs, {});
    RenderOptions o;
    o.alpha = true;
    const Image with = render(c->cs, o);
    REQUIRE(with.channels == 4);
    REQUIRE(plain.channels == 3);
    // The corner: nothing there. The centre: all sphere, the same colour as without alpha.
    CHECK(with.at(0, 0, 3) == 0.0f);
    for (int ch = 0; ch < 3; ++ch) CHECK(with.at(0, 0, ch) == 0.0f);
    CHECK(with.at(24, 16, 3) == 1.0f);
    for (int ch = 0; ch < 3; ++ch) CHECK(with.at(24, 16, ch) == Approx(plain.at(24, 16, ch)).margin(1e-6));
    // Everywhere: the plain picture is the premultiplied one over the background.
    const float bg[3] = {0.2f, 0.4f, 0.6f};
    int partial = 0;
    double worst = 0;
    for (int y = 0; y < with.height; ++y)
        for (int x = 0; x < with.width; ++x) {
            const float a = with.at(x, y, 3);
            partial += a > 0.0f && a < 1.0f;
            for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, double(std::fabs(with.at(x, y, ch) + (1 - a) * bg[ch] - plain.at(x, y, ch))));
        }
    CHECK(partial > 10);  // the sphere's edge, at 4 samples
    CHECK(worst < 1e-5);
}

TEST_CASE("EXR: R G B A Z N.x N.y N.z steps.Y, a miss at Z = +inf", "[image][alpha]") {
    const fs::path dir = dir_for("exr");
    auto c = test::compile_text(kScene);
    RenderOptions o;
    o.alpha = true;
    o.aovs = {"depth", "normal", "steps"};
    const Image img = render(c->cs, o);
    const std::string exr = (dir / "out.exr").string();
    write_image(exr, img);
    auto in = OIIO::ImageInput::open(exr);
    REQUIRE(in);
    const OIIO::ImageSpec& spec = in->spec();
    CHECK(spec.channelnames == std::vector<std::string>{"R", "G", "B", "A", "Z", "N.x", "N.y", "N.z", "steps.Y"});
    CHECK(spec.alpha_channel == 3);
    CHECK(spec.z_channel == 4);
    std::vector<float> px(size_t(spec.width) * spec.height * 9);
    REQUIRE(in->read_image(0, 0, 0, 9, OIIO::TypeDesc::FLOAT, px.data()));
    CHECK(px[4] == INFINITY);                                    // the corner: a miss
    CHECK(px[(16 * 48 + 24) * 9 + 4] == Approx(4.0f).margin(0.01f));  // the sphere's front
    CHECK(px[(16 * 48 + 24) * 9 + 3] == 1.0f);
    const Image back = read_image(exr);
    REQUIRE(back.aov("steps"));
    CHECK(back.aov("depth")->data[0] == INFINITY);
    fs::remove_all(dir);
}

TEST_CASE("8-bit files hold straight colour with alpha, hdr has none, its side files are float", "[image][alpha]") {
    const fs::path dir = dir_for("png");
    auto c = test::compile_text(kScene);
    RenderOptions o;
    o.alpha = true;
    const Image img = render(c->cs, o);
    const std::string png = (dir / "a.png").string();
    write_image(png, img);
    auto in = OIIO::ImageInput::open(png);
    REQUIRE(in);
    CHECK(in->spec().nchannels == 4);
    std::vector<uint8_t> px(size_t(48) * 32 * 4);
    in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, px.data());
    CHECK(px[3] == 0);
    CHECK(px[(16 * 48 + 24) * 4 + 3] == 255);
    CHECK(px[(16 * 48 + 24) * 4 + 0] == uint8_t(std::lround(linear_to_srgb(img.at(24, 16, 0)) * 255)));
    CHECK_THROWS_WITH(write_image((dir / "a.hdr").string(), img),
                      "cannot write '" + (dir / "a.hdr").string() + "': hdr has no alpha channel (exr, png, tif and tga have)");
    CHECK_THROWS_WITH(write_image((dir / "a.jpg").string(), img),
                      "cannot write '" + (dir / "a.jpg").string() + "': jpg has no alpha channel (exr, png, tif and tga have)");
    CHECK(!fs::exists(dir / "a.jpg"));

    // Beside a float picture, the AOV side files are EXR with the planes' own values.
    RenderOptions f;
    f.aovs = {"depth", "normal"};
    const Image planes = render(c->cs, f);
    const std::string hdr = (dir / "f.hdr").string();
    write_image(hdr, planes);
    CHECK(aov_side_path(hdr, "depth") == (dir / "f.depth.exr").string());
    const Image depth = read_image((dir / "f.depth.exr").string());
    REQUIRE(depth.aov("depth"));
    CHECK(depth.aov("depth")->data[16 * 48 + 24] == Approx(4.0f).margin(0.01f));
    const Image normal = read_image((dir / "f.normal.exr").string());
    REQUIRE(normal.aov("normal"));
    CHECK(normal.aov("normal")->data[(16 * 48 + 24) * 3 + 2] == Approx(1.0f).margin(0.01f));
    CHECK(aov_side_path((dir / "f.png").string(), "depth") == (dir / "f.depth.png").string());
    fs::remove_all(dir);
}

TEST_CASE("pgm is grey: the colour's luminance, one channel, and no alpha", "[image][alpha]") {
    const fs::path dir = dir_for("pgm");
    auto c = test::compile_text(kScene);
    const Image img = render(c->cs, RenderOptions{});
    const std::string pgm = (dir / "a.pgm").string();
    write_image(pgm, img);
    auto in = OIIO::ImageInput::open(pgm);
    REQUIRE(in);
    CHECK(in->spec().nchannels == 1);
    std::vector<uint8_t> px(size_t(48) * 32);
    in->read_image(0, 0, 0, 1, OIIO::TypeDesc::UINT8, px.data());
    const float* p = &img.pixels[(16 * 48 + 24) * 3];
    CHECK(px[16 * 48 + 24] == uint8_t(std::lround(linear_to_srgb(0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2]) * 255)));
    CHECK(px[16 * 48 + 24] != px[0]);  // the sphere against the background
    RenderOptions o;
    o.alpha = true;
    CHECK_THROWS_WITH(write_image(pgm, render(c->cs, o)), "cannot write '" + pgm + "': pgm has no alpha channel (exr, png, tif and tga have)");
    fs::remove_all(dir);
}
