// Batch at cluster scale (issue 19): --shard from the flag and from Slurm's and Kubernetes'
// variables, byte-identical re-runs, --skip-existing, and --tiles bands that sdfc merge puts
// together into the very picture one render makes.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <set>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

const char* kAnim = "camera(position = [0, 1, 5]);\nrotate([0, time * 40, 0]) box([1.5, 1, 0.6]);\nplane();\n";

// The frames a task wrote into `dir` (names), after clearing it.
std::set<std::string> frames_of(const std::string& dir) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
    return names;
}

std::string fresh_dir(const std::string& name) {
    const std::string d = test::temp_dir() + "/" + name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

}  // namespace

TEST_CASE("render --shard I/N renders the frames k with k mod N = I, and the variables of Slurm and Kubernetes say I and N") {
    const std::string s = test::write_temp("shard.sdf", kAnim);
    const std::string render = "render " + q(s) + " --frames 0:5 --width 16 --height 12 -q -o ";
    struct Case {
        std::string env, flag;
        std::set<std::string> want;
    };
    const std::vector<Case> cases = {
        {"", "--shard 1/3", {"f0001.png", "f0004.png"}},
        {"SLURM_ARRAY_TASK_ID=2 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_COUNT=4", "", {"f0002.png"}},
        {"SLURM_ARRAY_TASK_ID=12 SLURM_ARRAY_TASK_MIN=10 SLURM_ARRAY_TASK_MAX=13", "--shard auto", {"f0002.png"}},
        {"SLURM_ARRAY_TASK_ID=0 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_COUNT=2", "", {"f0000.png", "f0002.png", "f0004.png"}},
        {"JOB_COMPLETION_INDEX=1 SDFC_SHARD_COUNT=2", "", {"f0001.png", "f0003.png", "f0005.png"}},
        {"JOB_COMPLETION_INDEX=1 SDFC_SHARD_COUNT=2", "--shard 0/1", {"f0000.png", "f0001.png", "f0002.png", "f0003.png", "f0004.png", "f0005.png"}},
    };
    for (const Case& c : cases) {
        INFO(c.env << " " << c.flag);
        const std::string dir = fresh_dir("shard");
        auto r = run_sdfc(render + q(dir + "/f{frame:04d}.png") + " " + c.flag, c.env);
        CHECK(r.status == 0);
        CHECK(r.err == "");
        CHECK(frames_of(dir) == c.want);
    }
    // Without -q the task says what it took on.
    auto told = run_sdfc("render " + q(s) + " --frames 0:5 --width 16 --height 12 -o " + q(fresh_dir("told") + "/f{frame}.png"),
                         "SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_COUNT=3");
    CHECK(told.err.rfind("sdfc: shard 1/3 (SLURM_ARRAY_TASK_ID): 2 of 6 pictures\n", 0) == 0);
    // A task with none of the pictures (more tasks than pictures) says so, and succeeds.
    const std::string none = fresh_dir("none");
    auto idle = run_sdfc("render " + q(s) + " --frames 0:5 --width 16 --height 12 -o " + q(none + "/f{frame}.png") + " --shard 7/8");
    CHECK(idle.status == 0);
    CHECK(idle.err == "sdfc: shard 7/8: none of the 6 pictures\n");
    CHECK(frames_of(none).empty());
    // One picture under a scheduler is not shared out (no flag); errors say why.
    const std::string one = fresh_dir("one");
    CHECK(run_sdfc("render " + q(s) + " --width 16 --height 12 -q -o " + q(one + "/a.png"), "SLURM_ARRAY_TASK_ID=3 SLURM_ARRAY_TASK_COUNT=4").status == 0);
    CHECK(fs::exists(one + "/a.png"));
    CHECK(run_sdfc(render + "x{frame}.png --shard auto").err == "sdfc: error: --shard auto: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set\n");
    CHECK(run_sdfc(render + "x{frame}.png", "JOB_COMPLETION_INDEX=2").err ==
          "sdfc: error: JOB_COMPLETION_INDEX is set but not the Job's completions: the shard count cannot be known (set SDFC_SHARD_COUNT to the "
          "completions, or give --shard I/N)\n");
    CHECK(run_sdfc(render + "x{frame}.png", "SLURM_ARRAY_TASK_ID=2").err ==
          "sdfc: error: SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT: the shard count cannot be known (give --shard I/N)\n");
    CHECK(run_sdfc(render + "x{frame}.png --shard 3/3").err == "sdfc: error: --shard must be from 0 to 2, not 3\n");
    CHECK(run_sdfc(render + "x{frame}.png --shard 2").err == "sdfc: error: --shard takes I/N (this task's index and the count), not '2'\n");
    CHECK(run_sdfc(render + "x{frame}.png --shard 2").status == 2);
}

TEST_CASE("shards together are the one-process render byte for byte, a re-run writes the same bytes, and --skip-existing") {
    const std::string s = test::write_temp("shard_same.sdf", kAnim);
    const std::string all = fresh_dir("all"), parts = fresh_dir("parts");
    const std::string flags = " --frames 0:5 --width 24 --height 16 --aov depth -q -o ";
    REQUIRE(run_sdfc("render " + q(s) + flags + q(all + "/f{frame:04d}.exr")).status == 0);
    for (int i = 0; i < 4; ++i)
        REQUIRE(run_sdfc("render " + q(s) + flags + q(parts + "/f{frame:04d}.exr") + " --shard " + std::to_string(i) + "/4").status == 0);
    REQUIRE(frames_of(all) == frames_of(parts));
    for (const std::string& f : frames_of(all)) {
        INFO(f);
        CHECK(test::slurp(all + "/" + f) == test::slurp(parts + "/" + f));
    }
    // A task run again (killed half way, retried) writes the same bytes.
    const std::string before = test::slurp(parts + "/f0003.exr");
    fs::remove(parts + "/f0003.exr");
    REQUIRE(run_sdfc("render " + q(s) + flags + q(parts + "/f{frame:04d}.exr") + " --shard 3/4").status == 0);
    CHECK(test::slurp(parts + "/f0003.exr") == before);
    // --skip-existing renders only what is missing: with AOV side files, all of a picture's files.
    const std::string png = fresh_dir("skip");
    const std::string pflags = " --frames 0:2 --width 24 --height 16 --aov depth -o " + q(png + "/f{frame}.png");
    REQUIRE(run_sdfc("render " + q(s) + pflags + " -q").status == 0);
    fs::remove(png + "/f1.png");
    fs::remove(png + "/f2.depth.png");
    const auto t0 = fs::last_write_time(png + "/f0.png");
    auto r = run_sdfc("render " + q(s) + pflags + " --skip-existing");
    CHECK(r.status == 0);
    CHECK(r.err.find("sdfc: skipped " + png + "/f0.png (it is there)\n") != std::string::npos);
    CHECK(r.err.find("sdfc: wrote " + png + "/f1.png") != std::string::npos);
    CHECK(r.err.find("sdfc: wrote " + png + "/f2.png") != std::string::npos);
    CHECK(fs::last_write_time(png + "/f0.png") == t0);
    CHECK(fs::exists(png + "/f1.png"));
    CHECK(fs::exists(png + "/f2.depth.png"));
    // An empty file (a `touch`, a failed tool) is no picture of ours: rendered.
    { std::ofstream(png + "/f1.png", std::ios::trunc); }
    r = run_sdfc("render " + q(s) + pflags + " --skip-existing");
    CHECK(r.status == 0);
    CHECK(r.err.find("sdfc: wrote " + png + "/f1.png") != std::string::npos);
    CHECK(fs::file_size(png + "/f1.png") > 0);
}

TEST_CASE("render --tiles bands and sdfc merge make the one-render picture, byte for byte") {
    const std::string s = test::write_temp("tiles.sdf", "camera(position = [0, 1, 5]);\ntorus(1, 0.4);\nplane();\n");
    const std::string dir = fresh_dir("tiles");
    const std::string size = " --width 50 --height 70 --samples 2 -q";
    for (const char* ext : {"png", "exr"}) {
        INFO(ext);
        REQUIRE(run_sdfc("render " + q(s) + size + " --aov depth,normal -o " + q(dir + "/one." + ext)).status == 0);
        std::string parts;
        for (int i = 0; i < 3; ++i) {
            const std::string part = dir + "/part" + std::to_string(i) + ".exr";
            REQUIRE(run_sdfc("render " + q(s) + size + " --aov depth,normal --tiles " + std::to_string(i) + "/3 -o " + q(part) +
                             (std::string(ext) == "exr" ? " --alpha on" : ""))
                        .status == 0);
            parts = " " + q(part) + parts;  // in any order
        }
        auto m = run_sdfc("merge" + parts + " -o " + q(dir + "/merged." + ext));
        CHECK(m.status == 0);
        CHECK(m.err == "sdfc: wrote " + dir + "/merged." + ext + " (50x70 from 3 bands)\n");
        CHECK(test::slurp(dir + "/merged." + ext) == test::slurp(dir + "/one." + ext));
        if (std::string(ext) == "png")
            for (const char* side : {"depth", "normal"})
                CHECK(test::slurp(dir + "/merged." + side + ".png") == test::slurp(dir + "/one." + side + ".png"));
    }
    // One band of one (a cluster script with N = 1): merge takes it.
    REQUIRE(run_sdfc("render " + q(s) + size + " --aov depth,normal --tiles 0/1 -o " + q(dir + "/only.exr")).status == 0);
    auto only = run_sdfc("merge " + q(dir + "/only.exr") + " -o " + q(dir + "/only.png"));
    CHECK(only.err == "sdfc: wrote " + dir + "/only.png (50x70 from 1 band)\n");
    CHECK(test::slurp(dir + "/only.png") == test::slurp(dir + "/one.png"));
    // What merge refuses, and what --tiles does.
    CHECK(run_sdfc("merge " + q(dir + "/part0.exr") + " " + q(dir + "/part2.exr") + " -o " + q(dir + "/x.png")).err.find("are in none of the bands") !=
          std::string::npos);
    CHECK(run_sdfc("merge " + q(dir + "/part0.exr") + " " + q(dir + "/part0.exr") + " " + q(dir + "/part1.exr") + " " + q(dir + "/part2.exr") +
                   " -o " + q(dir + "/x.png"))
              .err.find("overlaps another band") != std::string::npos);
    CHECK(run_sdfc("merge " + q(dir + "/one.exr") + " -o " + q(dir + "/x.png")).err ==
          "sdfc: error: '" + dir + "/one.exr' is a whole picture, not a band of one (render --tiles I/N)\n");
    CHECK(run_sdfc("render " + q(s) + size + " --tiles 0/2 -o " + q(dir + "/p.png")).err ==
          "sdfc: error: --tiles writes a band of the picture as exr (for sdfc merge): -o PART.exr\n");
    auto nine = run_sdfc("render " + q(s) + size + " --tiles 0/9 -o " + q(dir + "/p.exr"));
    CHECK(nine.status == 2);  // (the command line asks what the picture cannot give)
    CHECK(nine.err == "sdfc: error: band 0 of 9: the picture has 5 rows of tiles (16 pixels each)\n");
    // A band of another scene, or of another frame, of the same size is another picture's.
    const std::string other = test::write_temp("tiles_other.sdf", "camera(position = [0, 1, 5]);\nsphere(1);\nplane();\n");
    REQUIRE(run_sdfc("render " + q(other) + size + " --aov depth,normal --tiles 1/3 --alpha on -o " + q(dir + "/other1.exr")).status == 0);
    auto mixed = run_sdfc("merge " + q(dir + "/part0.exr") + " " + q(dir + "/other1.exr") + " " + q(dir + "/part2.exr") + " -o " + q(dir + "/x.png"));
    CHECK(mixed.status == 1);
    CHECK(mixed.err == "sdfc: error: '" + dir + "/other1.exr' is a band of another picture than '" + dir +
                           "/part0.exr' (another scene, frame, setting, AOV or N of --tiles I/N)\n");
    auto self = run_sdfc("merge " + q(dir + "/part0.exr") + " -o " + q(dir + "/part0.exr"));
    CHECK(self.status == 1);
    CHECK(self.err == "sdfc: error: cannot write '" + dir + "/part0.exr': it is one of the bands merged ('" + dir + "/part0.exr')\n");
    CHECK_FALSE(fs::exists(dir + "/x.png"));
}

TEST_CASE("a batch's outputs, every frame's and every side file, are checked against each other and every input before any work") {
    const std::string d = fresh_dir("batch_inputs");
    auto write = [&](const std::string& name, const std::string& text) { std::ofstream(d + "/" + name, std::ios::binary) << text; };
    const std::string in_d = "cd " + q(d) + " &&";  // (run_sdfc's prefix)
    write("y.sdf", "render(width = 16, height = 12);\nsphere(1);\n");
    write("xy.png", "render(width = 16, height = 12);\nsphere(1);\n");  // a script named like a picture
    // One scene's picture onto another scene of the batch: refused, in either order.
    for (const std::string scenes : {"xy.png y.sdf", "y.sdf xy.png"}) {
        auto r = run_sdfc("render " + scenes + " -o 'x{name}.png' -q", in_d);
        CHECK(r.status == 1);
        CHECK(r.err == "sdfc: error: cannot write 'xy.png': it is the scene file 'xy.png'\n");
        CHECK(test::slurp(d + "/xy.png") == "render(width = 16, height = 12);\nsphere(1);\n");
    }
    // Onto a file another scene imports.
    write("part.png", "def part() = sphere(1);\n");
    write("a.sdf", "import \"part.png\";\nrender(width = 16, height = 12);\npart();\n");
    write("part.sdf", "render(width = 16, height = 12);\nbox(1);\n");
    auto r = run_sdfc("render a.sdf part.sdf -o '{name}.png' -q", in_d);
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot write 'part.png': a scene imports it ('part.png')\n");
    CHECK(!fs::exists(d + "/a.png"));
    // A side file onto another scene's picture.
    r = run_sdfc("render y.sdf y.depth.sdf -o '{name}.png' --aov depth -q", in_d);
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: the depth side file of 'y.sdf' and 'y.depth.sdf' would both be written to 'y.depth.png'\n");
    // Every frame's output is checked, not the first and last only.
    fs::create_directories(d + "/f2.png");
    r = run_sdfc("render y.sdf --frames 0:4 -o 'f{frame}.png' -q", in_d);
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot write 'f2.png': Is a directory\n");
    CHECK(!fs::exists(d + "/f0.png"));
    // A zero-padded width of two digits.
    r = run_sdfc("render y.sdf --frames 7:7 -o 'g{frame:010d}.png' -q", in_d);
    CHECK(r.status == 0);
    CHECK(fs::exists(d + "/g0000000007.png"));
}

TEST_CASE("a 2D model renders whole: --tiles, --aov, --alpha on and --view steps are refused, unused scene flags named") {
    const std::string d = fresh_dir("model_2d");
    const std::string vm = d + "/disc.vm";
    std::ofstream(vm) << "_0 var-x\n_1 var-y\n_2 square _0\n_3 square _1\n_4 add _2 _3\n_5 const 0.5\n_6 sub _4 _5\n";
    const std::string sphere = test::write_temp("model_2d_sphere.sdf", "sphere(1);\n");
    const std::string size = " --width 32 --height 32 ";
    const std::string what = "' is a 2D model, rendered whole as its sign image (white inside, black outside): no bands, AOVs, alpha or step view\n";
    const std::vector<std::pair<std::string, std::string>> asks{
        {"--tiles 0/2", "--tiles"}, {"--aov depth", "--aov"}, {"--alpha on", "--alpha on"}, {"--view steps", "--view steps"}};
    for (const auto& [flag, named] : asks) {
        INFO(flag);
        // (in a batch, before the other scene's picture is written; --tiles takes one scene)
        const bool tiles = named == "--tiles";
        auto r = run_sdfc("render " + (tiles ? std::string() : q(sphere) + " ") + q(vm) + size + flag + " -o " +
                          q(d + (tiles ? "/b.exr" : "/{name}.png")));
        CHECK(r.status == 2);
        CHECK(r.err == "sdfc: error: " + named + ": '" + vm + what);
    }
    CHECK(frames_of(d) == std::set<std::string>{"disc.vm"});
    auto r = run_sdfc("render " + q(vm) + size + "--samples 4 --fov 30 -o " + q(d + "/disc.png"));
    CHECK(r.status == 0);
    CHECK(r.err.rfind("sdfc: warning: '" + vm + "' is a 2D model, rendered as its sign image: --samples, --fov change nothing\n", 0) == 0);
}
