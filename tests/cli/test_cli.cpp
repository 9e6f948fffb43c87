// The sdfc command end to end (LANGUAGE.md section 10).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>

#include "run.hpp"
#include "runtime/io/image.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

TEST_CASE("the flags --help and --version") {
    auto h = run_sdfc("--help");
    CHECK(h.status == 0);
    CHECK(h.out.find("sdfc render SCENE") != std::string::npos);
    auto v = run_sdfc("--version");
    CHECK(v.status == 0);
    CHECK(v.out.rfind("sdfc ", 0) == 0);
    auto rh = run_sdfc("render --help");
    CHECK(rh.status == 0);
    CHECK(rh.out.rfind("usage: sdfc render SCENE... -o OUT [options]\n", 0) == 0);  // that command only
    CHECK(rh.out.find("sdfc glsl") == std::string::npos);
    CHECK(rh.out.find("\nscene options (-D, and the safety limits: docs/language.md):\n") != std::string::npos);
    CHECK(run_sdfc("mesh --help").out.rfind("usage: sdfc mesh SCENE -o OUT.stl|obj|ply|3mf [options]\n", 0) == 0);
    auto bad = run_sdfc("rendr x.sdf");
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: unknown command 'rendr' (did you mean `render`?)\n");
    auto none = run_sdfc("");
    CHECK(none.status == 2);
    CHECK(none.err.find("usage:") != std::string::npos);
}

TEST_CASE("a bad command line exits 2 and a bad script 1, unknown options get did-you-mean, -- ends options") {
    const std::string s = test::write_temp("exit_codes.sdf", "sphere(1);\n");
    auto typo = run_sdfc("render '" + s + "' -o x.png --widht 8");
    CHECK(typo.status == 2);
    CHECK(typo.err == "sdfc: error: unknown option '--widht' (did you mean `--width`?)\n");
    auto far = run_sdfc("check '" + s + "' --zzzzzzzz");
    CHECK(far.status == 2);
    CHECK(far.err == "sdfc: error: unknown option '--zzzzzzzz' (see --help)\n");
    CHECK(run_sdfc("eval '" + s + "' --at 1,2,3,4").status == 2);
    const std::string bad = test::write_temp("exit_codes_bad.sdf", "sphere(;\n");
    CHECK(run_sdfc("check '" + bad + "'").status == 1);
    // After --, a name that starts with '-' is a scene file.
    CHECK(run_sdfc("check -no-such.sdf").status == 2);
    auto r = run_sdfc("check -- -no-such.sdf");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot open '-no-such.sdf': No such file or directory\n");
    auto ok = run_sdfc("eval --at 0,0,0 -- '" + s + "'");
    CHECK(ok.status == 0);
    CHECK(ok.out == "-1\n");
    // An option and its short form, both given.
    auto both = run_sdfc("render '" + s + "' --quiet -q --width 8 --height 8 -o '" + test::temp_dir() + "/both.png'");
    CHECK(both.status == 0);
    CHECK(both.err.empty());
}

TEST_CASE("a number out of range is quoted as typed, and {name} of standard input is stdin") {
    std::string s = test::write_temp("range.sdf", "sphere(1);\n");
    auto r = run_sdfc("render '" + s + "' --width 99999999999999999999 -o '" + test::temp_dir() + "/range.png'");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --width must be from 1 to 16384, not 99999999999999999999\n");
    // Past a float's range either way: named so, not "not a number", nor "must be positive" of a 0.
    r = run_sdfc("render '" + s + "' --frames 0:1 --fps 1e-300 -o '" + test::temp_dir() + "/range{frame}.png'");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --fps 1e-300: the number is too small for a float (sdfc computes in floats)\n");
    r = run_sdfc("render '" + s + "' --time 1e300 -o '" + test::temp_dir() + "/range.png'");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: --time 1e300: the number is too large for a float (sdfc computes in floats)\n");
    const std::string out = test::temp_dir() + "/{name}.png";
    auto in = run_sdfc("render - --width 8 --height 8 -q -o '" + out + "'", "", s);
    CHECK(in.status == 0);
    CHECK(std::filesystem::exists(test::temp_dir() + "/stdin.png"));
}

TEST_CASE("eval prints one distance per line") {
    std::string s = test::write_temp("eval.sdf", "sphere(1);\ntranslate([3, 0, 0]) box(2);\n");
    auto r = run_sdfc("eval '" + s + "' --at 0,0,0");
    CHECK(r.status == 0);
    CHECK(r.out == "-1\n");
    std::string pts = test::write_temp("pts.txt", "2 0 0\n3 0 0\n0 0 0\n\n0 5 0\n");
    auto r2 = run_sdfc("eval '" + s + "' --points '" + pts + "'");
    CHECK(r2.status == 0);
    CHECK(r2.out == "0\n-1\n-1\n4\n");
    std::string neg = test::write_temp("eval_neg.sdf", "field (p) -> -p.x;\n");
    CHECK(run_sdfc("eval '" + neg + "' --at 0,0,0").out == "0\n");  // never "-0"
    auto bad = run_sdfc("eval '" + s + "' --at 1,2");
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: --at takes 3 comma-separated numbers, not '1,2'\n");
    // A bad line of a points file is an input file's error: its place, the line, a caret.
    std::string few = test::write_temp("pts_few.txt", "1 2 3\n4 5\n");
    auto r3 = run_sdfc("eval '" + s + "' --points '" + few + "'");
    CHECK(r3.status == 1);
    CHECK(r3.err == few + ":2:4: error: expected three numbers \"x y z\"\n4 5\n   ^\n");
    std::string word = test::write_temp("pts_word.txt", "1 2 3\r\n 4 x 5\r\n");
    auto r4 = run_sdfc("eval '" + s + "' --points '" + word + "'");
    CHECK(r4.status == 1);
    CHECK(r4.err.rfind(word + ":2:4: error: expected three numbers \"x y z\"\n", 0) == 0);
    std::string many = test::write_temp("pts_many.txt", "1 2 3 4\n");
    CHECK(run_sdfc("eval '" + s + "' --points '" + many + "'").err.rfind(many + ":1:7: error: expected three numbers \"x y z\", not more\n", 0) == 0);
    // Commas as --at takes them (a CSV file), after a byte-order mark too.
    std::string csv = test::write_temp("pts.csv", "\xEF\xBB\xBF" "2,0,0\n0, 5, 0\n");
    auto r5 = run_sdfc("eval '" + s + "' --points '" + csv + "'");
    CHECK(r5.status == 0);
    CHECK(r5.out == "0\n4\n");
}

TEST_CASE("check reports script errors with a caret and exit 1") {
    std::string s = test::write_temp("bad.sdf", "sphere(1);\nbox(2, 3);\n");
    auto r = run_sdfc("check '" + s + "'");
    CHECK(r.status == 1);
    CHECK(r.err == s + ":2:8: error: box takes at most 1 argument (size), but more were given\nbox(2, 3);\n       ^\n");
    auto ok = run_sdfc("check '" + test::example("three-tori.sdf") + "'");
    CHECK(ok.status == 0);
    CHECK(ok.err.empty());
    auto missing = run_sdfc("check /nonexistent/x.sdf");
    CHECK(missing.status == 1);
    CHECK(missing.err == "sdfc: error: cannot open '/nonexistent/x.sdf': No such file or directory\n");
}

TEST_CASE("render writes the image, an error leaves no file") {
    std::string out = test::temp_dir() + "/tori.png";
    fs::remove(out);
    auto r = run_sdfc("render '" + test::example("three-tori.sdf") + "' -o '" + out + "' --width 160 --height 90 --samples 1 --quiet");
    CHECK(r.status == 0);
    REQUIRE(fs::exists(out));
    Image img = read_image(out);
    CHECK(img.width == 160);
    CHECK(img.height == 90);
    // Nothing but the image in the folder: no temp files left behind.
    for (const auto& e : fs::directory_iterator(test::temp_dir()))
        CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);

    std::string bad = test::write_temp("bad2.sdf", "sphere(;\n");
    std::string out2 = test::temp_dir() + "/never.png";
    auto e = run_sdfc("render '" + bad + "' -o '" + out2 + "'");
    CHECK(e.status == 1);
    CHECK(!fs::exists(out2));
    CHECK(e.err.rfind(bad + ":1:8: error:", 0) == 0);
}

TEST_CASE("render --frames writes one file per frame, and they differ where the scene moves") {
    std::string s = test::write_temp("anim.sdf",
        "camera(position = [0, 0, 6]);\nrender(width = 64, height = 48);\ntranslate([sin(time * 3) * 1.5, 0, 0]) sphere(0.8);\n");
    std::string pattern = test::temp_dir() + "/frame_{frame:04d}.png";
    auto r = run_sdfc("render '" + s + "' -o '" + pattern + "' --frames 0:3 --fps 4 --quiet");
    CHECK(r.status == 0);
    std::vector<Image> frames;
    for (int f = 0; f <= 3; ++f) {
        std::string p = test::temp_dir() + "/frame_000" + std::to_string(f) + ".png";
        REQUIRE(fs::exists(p));
        frames.push_back(read_image(p));
    }
    CHECK(frames[0].pixels != frames[1].pixels);
    CHECK(frames[1].pixels != frames[2].pixels);
    auto bad = run_sdfc("render '" + s + "' -o '" + test::temp_dir() + "/x.png' --frames 0:3");
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: rendering several frames needs {frame:04d} in the output name\n");
}

TEST_CASE("output names: a malformed or unknown placeholder, and two pictures to one file, are refused before any work") {
    std::string s = test::write_temp("names.sdf", "render(width = 8, height = 8);\nsphere(1);\n");
    fs::path dir = fs::path(test::temp_dir()) / "names";
    fs::remove_all(dir);
    fs::create_directories(dir / "d1");
    fs::create_directories(dir / "d2");
    auto render = [&](const std::string& scenes, const std::string& out, const std::string& more) {
        return run_sdfc("render " + scenes + " -o '" + (dir / out).string() + "' --quiet " + more);
    };
    const std::string d = (dir / "").string();
    auto r = render("'" + s + "'", "f{frame.png", "--frames 0:2");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: the output name '" + d + "f{frame.png' has a '{' with no '}' (known: {frame:04d}, {frame}, {name})\n");
    r = render("'" + s + "'", "f{frme}.png", "");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: unknown '{frme}' in the output name '" + d +
                       "f{frme}.png' (known: {frame:04d}, {frame}, {name}; write {{ and }} for braces)\n");
    r = render("'" + s + "'", "f}.png", "");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: the output name '" + d + "f}.png' has a '}' with no '{' (write }} for a brace)\n");
    r = render("'" + s + "'", "f{frame:x4d}.png", "--frames 0:1");
    CHECK(r.err == "sdfc: error: unsupported frame format '{frame:x4d}' (use {frame:04d})\n");
    CHECK(fs::is_empty(dir / "d1"));
    // Braces doubled are braces.
    r = render("'" + s + "'", "b{{{frame}}}.png", "--frames 1:2");
    CHECK(r.status == 0);
    CHECK(fs::exists(dir / "b{1}.png"));
    CHECK(fs::exists(dir / "b{2}.png"));
    // Two scenes of one file name, or one scene twice: refused, nothing written.
    const std::string a = test::write_temp("names_d1.sdf", "sphere(1);\n");
    fs::copy_file(a, dir / "d1" / "x.sdf", fs::copy_options::overwrite_existing);
    fs::copy_file(a, dir / "d2" / "x.sdf", fs::copy_options::overwrite_existing);
    r = render("'" + (dir / "d1" / "x.sdf").string() + "' '" + (dir / "d2" / "x.sdf").string() + "'", "{name}.png", "");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: '" + (dir / "d1" / "x.sdf").string() + "' and '" + (dir / "d2" / "x.sdf").string() +
                       "' would both be written to '" + d + "x.png' ({name} is the file name without its folder and extension)\n");
    CHECK(!fs::exists(dir / "x.png"));
    r = run_sdfc("render '" + s + "' -o - --format png --frames 0:1");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: standard output (-o -) takes one picture: give the frames a file name with {frame:04d}\n");
}

TEST_CASE("an animation whose script fails at a later frame writes no frame and names it") {
    std::string s = test::write_temp("anim_fail.sdf", "render(width = 16, height = 12);\nsphere(1 - time);\n");
    fs::path dir = fs::path(test::temp_dir()) / "anim_fail";
    fs::remove_all(dir);
    fs::create_directories(dir);
    auto r = run_sdfc("render '" + s + "' -o '" + (dir / "f{frame:04d}.png").string() + "' --frames 0:3 --fps 1 --quiet");
    CHECK(r.status == 1);
    CHECK(r.err.substr(0, r.err.find('\n')) ==
          s + ":2:10: error: argument 'r' of sphere must be zero or positive, not -1 (at frame 2, time 2)");
    CHECK(fs::is_empty(dir));
}

TEST_CASE("compile --emit lists the AST, the IR and the bytecode") {
    std::string s = test::write_temp("emit.sdf", "translate([1, 0, 0]) sphere(0.5);\n");
    auto ast = run_sdfc("compile '" + s + "' --emit ast");
    CHECK(ast.status == 0);
    CHECK(ast.out.find("sphere") != std::string::npos);
    auto ir = run_sdfc("compile '" + s + "' --emit ir");
    CHECK(ir.status == 0);
    CHECK(ir.out.find("length3") != std::string::npos);
    auto bc = run_sdfc("compile '" + s + "' --emit bytecode");
    CHECK(bc.status == 0);
    CHECK(bc.out.find("; distance program") != std::string::npos);
    CHECK(bc.out.find("add_i") != std::string::npos);
    auto bad = run_sdfc("compile '" + s + "' --emit tokens");
    CHECK(bad.status == 2);
    CHECK(bad.err == "sdfc: error: --emit takes ast, ir or bytecode, not 'tokens'\n");
}

TEST_CASE("slice writes a cross-section picture") {
    std::string out = test::temp_dir() + "/slice.png";
    auto r = run_sdfc("slice '" + test::example("three-tori.sdf") + "' --axis z --at 0 -o '" + out + "' --width 200");
    CHECK(r.status == 0);
    REQUIRE(fs::exists(out));
    Image img = read_image(out);
    CHECK(img.width == 200);
    // Width and height both given: pixels stay square, so a sphere's section is a circle.
    std::string sph = test::write_temp("slice_sphere.sdf", "sphere(1);\n");
    std::string out2 = test::temp_dir() + "/slice_sphere.png";
    REQUIRE(run_sdfc("slice '" + sph + "' --axis z --at 0 -o '" + out2 + "' --width 160 --height 120").status == 0);
    Image s2 = read_image(out2);
    REQUIRE((s2.width == 160 && s2.height == 120));
    auto inside = [&](int x, int y) {  // the palette: cool (blue over red) inside
        const float* px = &s2.pixels[(size_t(y) * s2.width + x) * s2.channels];
        return px[2] > px[0];
    };
    int across = 0, down = 0;
    for (int x = 0; x < s2.width; ++x) across += inside(x, s2.height / 2);
    for (int y = 0; y < s2.height; ++y) down += inside(s2.width / 2, y);
    CHECK(across > 40);
    CHECK(std::abs(across - down) <= 2);
}

namespace {
// The value of `key=` in a bench result line.
double field(const std::string& line, const std::string& key) {
    const size_t at = line.find(" " + key + "=") != std::string::npos ? line.find(" " + key + "=") + 1 : line.rfind(key + "=", 0);
    REQUIRE(at != std::string::npos);
    return std::stod(line.substr(at + key.size() + 1));
}
}  // namespace

TEST_CASE("bench prints one line of times and evaluations, --baseline evaluates more") {
    const std::string scene = test::example("three-tori.sdf");
    auto fast = run_sdfc("bench '" + scene + "' --width 96 --height 54 --samples 1 --repeat 2 --threads 2");
    REQUIRE(fast.status == 0);
    INFO(fast.out);
    CHECK(fast.out.rfind("median_ms=", 0) == 0);
    CHECK(std::count(fast.out.begin(), fast.out.end(), '\n') == 1);
    for (const char* k : {"min_ms", "evals_per_pixel", "rays", "normals", "shadows", "ao", "shading", "tree_leaves"})
        CHECK(field(fast.out, k) >= 0.0);
    // The kinds add up to the SDF evaluations.
    const double sum = field(fast.out, "rays") + field(fast.out, "normals") + field(fast.out, "shadows") + field(fast.out, "ao");
    CHECK(sum == Approx(field(fast.out, "evals_per_pixel")).margin(0.03));
    auto base = run_sdfc("bench '" + scene + "' --width 96 --height 54 --samples 1 --repeat 1 --baseline");
    REQUIRE(base.status == 0);
    CHECK(field(base.out, "rays") > field(fast.out, "rays"));
    // Normals are four taps per hit either way: (nearly) the same hits.
    CHECK(field(base.out, "normals") == Approx(field(fast.out, "normals")).epsilon(0.02));
    // --samples multiplies the camera rays.
    auto s4 = run_sdfc("bench '" + scene + "' --width 96 --height 54 --samples 4 --repeat 1");
    REQUIRE(s4.status == 0);
    CHECK(field(s4.out, "rays") > 3.0 * field(fast.out, "rays"));
}

TEST_CASE("bench's later renders take the tape tree the first kept, --fresh-tree builds one each render") {
    const std::string scene = test::example("showcase.sdf");
    auto kept = run_sdfc("bench '" + scene + "' --width 96 --height 54 --repeat 1 --warmup 1 --threads 2");
    auto fresh = run_sdfc("bench '" + scene + "' --width 96 --height 54 --repeat 1 --warmup 1 --threads 2 --fresh-tree");
    REQUIRE(kept.status == 0);
    REQUIRE(fresh.status == 0);
    INFO(kept.out << fresh.out);
    CHECK(field(kept.out, "tree_leaves") > 0);
    CHECK(field(kept.out, "tree_reused") == 1);
    CHECK(field(fresh.out, "tree_reused") == 0);
    // The same tree either way, and the same evaluations.
    CHECK(field(fresh.out, "tree_leaves") == field(kept.out, "tree_leaves"));
    CHECK(field(fresh.out, "evals_per_pixel") == field(kept.out, "evals_per_pixel"));
}

TEST_CASE("bench --warmup: untimed renders first, the first render's time apart as cold_ms") {
    const std::string scene = test::example("three-tori.sdf");
    auto none = run_sdfc("bench '" + scene + "' --width 32 --height 18 --repeat 1 --warmup 0");
    REQUIRE(none.status == 0);
    INFO(none.out);
    // Without warm-up the one timed render is the first: its time is the cold one.
    CHECK(field(none.out, "cold_ms") == field(none.out, "median_ms"));
    auto some = run_sdfc("bench '" + scene + "' --width 32 --height 18 --repeat 1 --warmup 3");
    REQUIRE(some.status == 0);
    CHECK(field(some.out, "cold_ms") > 0.0);
    auto bad = run_sdfc("bench '" + scene + "' --warmup -1");
    CHECK(bad.status == 2);
    CHECK(bad.err.find("--warmup must be from 0 to 100000, not -1") != std::string::npos);
}

TEST_CASE("the html page's title is the script's file name as it is, a GLSL comment's in ASCII") {
    const std::string s = test::write_temp("\xc3\xa9volution.sdf", "sphere(1);\n");
    const std::string page = test::temp_dir() + "/evolution.html";
    REQUIRE(run_sdfc("glsl '" + s + "' --target html -o '" + page + "'").status == 0);
    const std::string html = test::slurp(page);
    CHECK(html.find("<title>\xc3\xa9volution.sdf - sdfc preview</title>") != std::string::npos);
    const auto r = run_sdfc("glsl '" + s + "'");
    CHECK(r.out.find("// Generated by sdfc from ?volution.sdf.") != std::string::npos);
}
