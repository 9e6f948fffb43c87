// Every safety limit through the sdfc command: the default stops the script with a located
// diagnostic (exit 1, no output file), and its flag raises it (docs/language.md, Limits).
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "run.hpp"

// Sanitizer builds (.ci/sanitize) differ in their stacks: see the nesting and depth tests.
#if defined(__SANITIZE_ADDRESS__)
#define SDFC_TEST_ASAN 1
#elif defined(__SANITIZE_THREAD__)
#define SDFC_TEST_TSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFC_TEST_ASAN 1
#elif __has_feature(thread_sanitizer)
#define SDFC_TEST_TSAN 1
#endif
#endif

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {

std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }

std::string repeat(const std::string& s, int n) {
    std::string out;
    for (int i = 0; i < n; ++i) out += s;
    return out;
}

// `sdfc check FILE FLAGS`: exit status and the first line of stderr.
std::pair<int, std::string> check(const std::string& file, const std::string& flags = "") {
    auto r = run_sdfc("check '" + file + "' " + flags);
    return {r.status, first_line(r.err)};
}

}  // namespace

TEST_CASE("flag --max-recursion") {
    std::string s = test::write_temp("lim_rec.sdf", "def f(n) = n > 0 ? f(n - 1) + 1 : 0;\nsphere(f(100) / 100);\n");
    CHECK(check(s) == std::pair<int, std::string>{1, s + ":1:20: error: recursion deeper than 64 calls in 'f' (raise it with --max-recursion)"});
    CHECK(check(s, "--max-recursion 101").first == 0);
    CHECK(check(s, "--max-recursion 0").second == "sdfc: error: --max-recursion must be from 1 to 100000, not 0");
}

TEST_CASE("flag --max-iterations (one loop, and all loops together)") {
    std::string s = test::write_temp("lim_it.sdf", "field (p) -> { var d = p.x; for (i = [1 : 150000]) d = d + 0; d };\n");
    CHECK(check(s) == std::pair<int, std::string>{1, s + ":1:38: error: this range has 150000 elements, over the loop limit of 100000 (raise it with --max-iterations)"});
    CHECK(check(s, "--max-iterations 150000").first == 0);
}

TEST_CASE("flag --max-calls") {
    std::string s = test::write_temp("lim_calls.sdf", "def f(n) = n > 0 ? f(n - 1) + f(n - 1) : 1;\nsphere(f(12) / 4096);\n");
    auto [st, err] = check(s, "--max-calls 1000");
    CHECK(st == 1);
    CHECK(err.find("error: the script made more than 1000 calls in all") != std::string::npos);
    CHECK(err.rfind(s + ":1:", 0) == 0);
    CHECK(check(s).first == 0);
}

TEST_CASE("flag --max-list (a list comprehension, concat)") {
    // concat needs no loop or call: a list doubled 20 times took 1.4 GB before this limit.
    std::string s = test::write_temp("lim_list.sdf", "let a = [for (i = [0 : 11]) i];\nlet b = concat(a, a);\nsphere(len(b) / 24);\n");
    CHECK(check(s, "--max-list 10") == std::pair<int, std::string>{1, s + ":1:9: error: a list of more than 10 elements (raise it with --max-list)"});
    CHECK(check(s, "--max-list 20") == std::pair<int, std::string>{1, s + ":2:9: error: a list of more than 20 elements (raise it with --max-list)"});
    CHECK(check(s, "--max-list 24").first == 0);
    CHECK(check(s).first == 0);
    CHECK(check(s, "--max-list 0").second == "sdfc: error: --max-list must be from 1 to 2000000000, not 0");
}

TEST_CASE("flag --max-shapes and --max-shape-depth") {
    std::string s = test::write_temp("lim_shapes.sdf", "for (i = [0 : 199]) translate([i, 0, 0]) sphere(0.4);\n");
    auto [st, err] = check(s, "--max-shapes 100");
    CHECK(st == 1);
    CHECK(err == s + ":1:42: error: the scene has more than 100 shapes (raise it with --max-shapes)");
    CHECK(check(s, "--max-shapes 1000").first == 0);
    // Once, though later statements make shapes too; "1 shape".
    const std::string two = test::write_temp("lim_shapes_two.sdf", "sphere(1);\nbox(1);\ntranslate([2, 0, 0]) box(1);\n");
    auto once = run_sdfc("check '" + two + "' --max-shapes 1");
    CHECK(once.status == 1);
    CHECK(once.err == two + ":2:1: error: the scene has more than 1 shape (raise it with --max-shapes)\nbox(1);\n^\n");
    std::string d = test::write_temp("lim_depth.sdf", "def f(n) = n > 0 ? translate([0, 0.1, 0]) f(n - 1) : sphere(1);\nf(30);\n");
    CHECK(check(d, "--max-shape-depth 10") ==
          std::pair<int, std::string>{1, d + ":1:20: error: shapes nested more than 10 deep (raise it with --max-shape-depth)"});
    CHECK(check(d).first == 0);
}

TEST_CASE("imports nested deeper than --max-nesting") {
    // A chain of files, each importing the next (each passes on all the names below it): the
    // top file and 7 more, the 8th import refused.
    for (int i = 0; i < 12; ++i)
        test::write_temp("lim_chain" + std::to_string(i) + ".sdf",
                         "import \"lim_chain" + std::to_string(i + 1) + ".sdf\";\ndef f" + std::to_string(i) + "() = 1;\n");
    test::write_temp("lim_chain12.sdf", "def z() = 1;\n");
    const std::string top = test::write_temp("lim_chain_top.sdf", "import \"lim_chain0.sdf\";\nsphere(z());\n");
    CHECK(check(top).first == 0);
    CHECK(check(top, "--max-nesting 8") ==
          std::pair<int, std::string>{1, test::temp_dir() + "/lim_chain6.sdf:1:1: error: imports nested deeper than 8 files (raise it with --max-nesting)"});
}

TEST_CASE("flag --max-ops") {
    std::string s = test::write_temp("lim_ops.sdf",
        "field (p) -> { var d = p.x; for (i = [1 : 100]) d = min(d, length(p - [i, 0, 0]) - 0.5); d };\n");
    auto [st, err] = check(s, "--max-ops 300");
    CHECK(st == 1);
    CHECK(err.find("error: the program grew past 300 operations (raise it with --max-ops)") != std::string::npos);
    CHECK(check(s).first == 0);
}

TEST_CASE("flag --max-nesting") {
    std::string s = test::write_temp("lim_nest.sdf", "sphere(" + repeat("(", 1100) + "1" + repeat(")", 1100) + ");\n");
    CHECK(check(s) == std::pair<int, std::string>{1, s + ":1:1032: error: nesting deeper than 1024 levels (raise it with --max-nesting)"});
    CHECK(check(s, "--max-nesting 2000").first == 0);
    CHECK(check(s, "--max-nesting 100000").second == "sdfc: error: --max-nesting must be from 1 to 10000, not 100000");
}

// The parser recurses once per nesting level; it must stop at the limit with a located error,
// never overflow the C++ stack (issue 7), whatever the stack of the build (sanitizer builds
// use several times more per level: the parser then moves to a thread with a bigger stack).
TEST_CASE("100,000 nested parentheses, blocks, minus signs, calls or modifiers stop at the nesting limit") {
    const int n = 100000;
    struct Case {
        const char* file;
        std::string text;
        std::string where;         // line:col of the error at the default limit (1024)
        std::string where_raised;  // ... and at --max-nesting 10000
        bool fits_asan, fits_tsan; // 10,000 levels fit the parser's stack in that sanitizer build
    };
    const std::vector<Case> cases{
        {"nest_parens.sdf", "sphere(" + repeat("(", n) + "1" + repeat(")", n) + ");\n", "1:1032", "1:10008", false, true},
        {"nest_blocks.sdf", repeat("{", n) + "sphere(1);" + repeat("}", n) + "\n", "1:1026", "1:10002", true, false},
        {"nest_minus.sdf", "sphere(" + repeat("-", n) + "1);\n", "1:1032", "1:10008", true, true},
        {"nest_calls.sdf", "def f(x) = x;\nsphere(" + repeat("f(", n) + "1" + repeat(")", n) + ");\n", "2:2056", "2:20008",
         false, false},
        // Each modifier is one level, and its argument list one more while it is read.
        {"nest_modifiers.sdf", repeat("translate([0,0,0]) ", n) + "sphere(1);\n", "1:19449", "1:189993", true, true},
    };
    for (const auto& c : cases) {
        INFO(c.file);
        std::string path = test::write_temp(c.file, c.text);
        CHECK(check(path) == std::pair<int, std::string>{1, path + ":" + c.where + ": error: nesting deeper than 1024 levels (raise it with --max-nesting)"});
        auto raised = check(path, "--max-nesting 10000");
        bool fits = true;
#if defined(SDFC_TEST_ASAN)
        fits = c.fits_asan;
#elif defined(SDFC_TEST_TSAN)
        fits = c.fits_tsan;
#endif
        if (fits) {
            CHECK(raised == std::pair<int, std::string>{1, path + ":" + c.where_raised + ": error: nesting deeper than 10000 levels (the most --max-nesting allows)"});
        } else {
            // Sanitizer builds cap the parser's stack (see parse() in lang/parser.cpp): the
            // stack guard stops these first, at a column that depends on the compiler.
            CHECK(raised.first == 1);
            CHECK(raised.second.rfind(path + ":" + c.where_raised.substr(0, 2), 0) == 0);
            CHECK(raised.second.find(": error: nested too deeply: the C++ stack is nearly exhausted (simplify the script, "
                                     "or run with a larger stack: ulimit -s)") != std::string::npos);
        }
    }
}

// The command runs on a thread with a big stack (cli/main.cpp), so scripts as deep as the
// default limits allow compile in every build, sanitizers included, instead of stopping
// at the stack guard (as they did under ASan on the main thread's 8 MB).
TEST_CASE("scripts as deep as the default limits allow compile") {
    std::string lets = "let a0 = sphere(1);\n";
    for (int i = 1; i < 3990; ++i) lets += "let a" + std::to_string(i) + " = translate([0.001, 0, 0]) a" + std::to_string(i - 1) + ";\n";
    lets += "a3989;\n";
    const std::string blocks = repeat("translate([0.001, 0, 0]) {\n", 500) + "sphere(1);\n" + repeat("}\n", 500);
    for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
             {"deep_lets.sdf", lets}, {"deep_blocks.sdf", blocks}}) {
        INFO(name);
        auto r = check(test::write_temp(name, text));
#if defined(SDFC_TEST_TSAN)
        // ThreadSanitizer caps the stack at 8 MB (compiler/base/stack.cpp): the guard may stop these.
        CHECK((r.first == 0 || r.second.find("the C++ stack is nearly exhausted") != std::string::npos));
#else
        CHECK(r == std::pair<int, std::string>{0, ""});
#endif
    }
}

TEST_CASE("flag --max-file-size") {
    std::string s = test::write_temp("lim_size.sdf", "// " + std::string(2000, '-') + "\nsphere(1);\n");
    CHECK(check(s, "--max-file-size 1000") ==
          std::pair<int, std::string>{1, "sdfc: error: '" + s + "' is 2015 bytes, over the limit of 1000 bytes (--max-file-size)"});
    CHECK(check(s).first == 0);
}

TEST_CASE("flag --max-pixels (width x height x samples) and --max-frames, no output is written") {
    std::string s = test::write_temp("lim_px.sdf", "render(width = 200, height = 100, samples = 4);\nsphere(1);\n");
    std::string out = test::temp_dir() + "/lim_px.png";
    fs::remove(out);
    auto r = run_sdfc("render '" + s + "' -o '" + out + "' --quiet --max-pixels 50000");
    CHECK(r.status == 1);
    CHECK(first_line(r.err) == s + ":1:1: error: 200x100 pixels at 4 samples is over the limit of 50000 (raise it with --max-pixels)");
    CHECK(!fs::exists(out));
    r = run_sdfc("render '" + s + "' -o '" + out + "' --quiet --width 300 --samples 1 --max-pixels 20000");
    CHECK(r.status == 2);
    CHECK(first_line(r.err) == "sdfc: error: 300x100 pixels at 1 samples is over the limit of 20000 (raise it with --max-pixels)");
    CHECK(!fs::exists(out));
    r = run_sdfc("render '" + s + "' -o '" + out + "' --quiet --width 20 --height 10 --samples 1 --max-pixels 200");
    CHECK(r.status == 0);
    CHECK(fs::exists(out));
    // With --tiles I/N the limit is one band's: height / N rows.
    const std::string band = test::temp_dir() + "/lim_band.exr";
    r = run_sdfc("render '" + s + "' -o '" + band + "' --quiet --width 64 --height 64 --samples 1 --tiles 0/2 --max-pixels 2000");
    CHECK(r.status == 2);
    CHECK(first_line(r.err) == "sdfc: error: 64x64 pixels at 1 samples (32 rows a band of 2) is over the limit of 2000 (raise it with --max-pixels)");
    r = run_sdfc("render '" + s + "' -o '" + band + "' --quiet --width 64 --height 64 --samples 1 --tiles 0/4 --max-pixels 2000");
    CHECK(r.status == 0);
    CHECK(fs::exists(band));

    std::string pattern = test::temp_dir() + "/lim_frame_{frame:04d}.png";
    r = run_sdfc("render '" + s + "' -o '" + pattern + "' --quiet --width 8 --height 8 --frames 0:9 --max-frames 5");
    CHECK(r.status == 2);
    CHECK(first_line(r.err) == "sdfc: error: 10 frames is over the limit of 5 (raise it with --max-frames)");
    CHECK(!fs::exists(test::temp_dir() + "/lim_frame_0000.png"));
    r = run_sdfc("render '" + s + "' -o '" + pattern + "' --quiet --width 8 --height 8 --samples 1 --frames 0:1 --max-frames 2");
    CHECK(r.status == 0);
    CHECK(fs::exists(test::temp_dir() + "/lim_frame_0001.png"));
}

// Memory that runs out is a plain error, not an exception's name (a picture the default
// --max-pixels allows can need more memory than the machine has). Not under the sanitizers,
// whose shadow memory a limit on the address space leaves no room for.
#if !defined(SDFC_TEST_ASAN) && !defined(SDFC_TEST_TSAN)
TEST_CASE("running out of memory is reported as such, exit 1, no output") {
    const std::string s = test::write_temp("oom.sdf", "sphere(1);\n");
    const std::string out = test::temp_dir() + "/oom.png";
    std::remove(out.c_str());
    auto r = run_sdfc("render '" + s + "' --width 8192 --height 8192 --threads 1 -o '" + out + "'", "ulimit -v 700000;");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: out of memory: the work is too big for this machine (a smaller picture, fewer samples, or lower "
                   "--max-* limits)\n");
    CHECK(!fs::exists(out));
}
#endif
