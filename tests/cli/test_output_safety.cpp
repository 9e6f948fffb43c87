// Issue 14: no output lost or misreported. A full disk, a device, a FIFO, a symlink, the
// script itself as the output, a signal during the write, a bad output path found only after
// the render, a long legal name, standard output that cannot be written: each ends with
// exit 1 and `sdfc: error:` naming the user's path and the reason, or with the output
// written as asked, and never with a replaced file or a temporary file left behind.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "run.hpp"
#include "runtime/io/image.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

std::string fresh_dir(const std::string& name) {
    std::string d = test::temp_dir() + "/" + name;
    ::umount2(d.c_str(), MNT_DETACH);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

std::string temps_in(const std::string& dir) {
    std::string names;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename().string().find(".tmp-") != std::string::npos) names += e.path().filename().string() + " ";
    return names;
}

// `sdfc ARGS` with standard output going to `out` (a shell redirection target).
test::RunResult run_to(const std::string& args, const std::string& out) {
    std::string exe = std::getenv("SDFC_BIN") ? std::getenv("SDFC_BIN") : SDFC_BIN_PATH;
    std::string err = test::temp_dir() + "/stderr_to.txt";
    int st = std::system(("'" + exe + "' " + args + " >" + out + " 2>'" + err + "' </dev/null").c_str());
    test::RunResult r;
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    r.err = test::slurp(err);
    return r;
}

// A tmpfs of `kb` KiB at `dir` (root only): false, with a warning, where it cannot be made.
bool mount_tmpfs(const std::string& dir, int kb, bool read_only = false) {
    std::string opts = "size=" + std::to_string(kb) + "k";
    if (::mount("tmpfs", dir.c_str(), "tmpfs", read_only ? MS_RDONLY : 0, opts.c_str()) != 0) {
        WARN("cannot mount a tmpfs (not root?): skipped");
        return false;
    }
    return true;
}

// Unmounts at the end of the scope, a failed REQUIRE included.
struct Unmount {
    std::string dir;
    ~Unmount() { ::umount2(dir.c_str(), MNT_DETACH); }
};

// Fills the file system of `dir` to the last byte.
void fill(const std::string& dir) {
    int fd = ::open((dir + "/filler").c_str(), O_WRONLY | O_CREAT, 0644);
    REQUIRE(fd >= 0);
    std::string block(4096, 'x');
    while (::write(fd, block.data(), block.size()) > 0) {}
    while (::write(fd, block.data(), 1) > 0) {}
    ::close(fd);
}

const char* kScene = "camera(position = [0, 0.5, 4]);\nsphere(1);\ntranslate([0, -1, 0]) box([5, 0.2, 5]);\n";

}  // namespace

TEST_CASE("a full disk: render slice JPEG and AOV side files fail with the reason and the old file stays") {
    const std::string dir = fresh_dir("full");
    if (!mount_tmpfs(dir, 64)) return;
    Unmount unmount{dir};
    std::string s = test::write_temp("full.sdf", kScene);
    for (const char* name : {"keep.png", "keep.jpg", "keep.exr"}) {
        const std::string out = dir + "/" + name;
        REQUIRE(run_sdfc("render " + q(s) + " -o " + q(out) + " --width 8 --height 8 --quiet").status == 0);
    }
    const std::string slice_out = dir + "/slice.png";
    REQUIRE(run_sdfc("slice " + q(s) + " --axis z --at 0 -o " + q(slice_out) + " --width 8 --height 8").status == 0);
    fill(dir);
    auto expect_failure = [&](const std::string& cmd, const std::string& out) {
        INFO(cmd);
        const std::string before = test::slurp(out);
        auto r = run_sdfc(cmd);
        INFO(r.err);
        CHECK(r.status == 1);
        CHECK(r.err.find("sdfc: error: cannot write '" + out + "': No space left on device") != std::string::npos);
        CHECK(r.err.find("wrote") == std::string::npos);
        CHECK(r.err.find(".tmp-") == std::string::npos);
        CHECK(test::slurp(out) == before);
        CHECK(temps_in(dir) == "");
    };
    for (const char* name : {"keep.png", "keep.jpg", "keep.exr"}) {
        const std::string out = dir + "/" + name;
        expect_failure("render " + q(s) + " -o " + q(out) + " --width 128 --height 96", out);
    }
    expect_failure("slice " + q(s) + " --axis z --at 0 -o " + q(slice_out) + " --width 128 --height 128", slice_out);
    // The side file goes first: its failure names it, and the main image is untouched.
    const std::string keep = dir + "/keep.png", before = test::slurp(keep);
    auto r = run_sdfc("render " + q(s) + " -o " + q(keep) + " --width 128 --height 96 --aov depth --quiet");
    CHECK(r.status == 1);
    CHECK(r.err.find("cannot write '" + dir + "/keep.depth.png': No space left on device") != std::string::npos);
    CHECK(test::slurp(keep) == before);
    CHECK(temps_in(dir) == "");
    // glsl -o too.
    const std::string glsl = dir + "/scene.glsl";
    r = run_sdfc("glsl " + q(s) + " -o " + q(glsl));
    CHECK(r.status == 1);
    CHECK(r.err.find("cannot write '" + glsl + "': No space left on device") != std::string::npos);
    CHECK(!fs::exists(glsl));
    CHECK(temps_in(dir) == "");
}

TEST_CASE("a character device or FIFO output is written through and a symlink stays a link") {
    const std::string dir = fresh_dir("nodes");
    std::string s = test::write_temp("nodes.sdf", kScene);
    // Copies of /dev/full and /dev/null made here (root only), so that an sdfc that gets this
    // wrong replaces the copies, never the machine's devices.
    const std::string full = dir + "/full", null = dir + "/null";
    struct stat st {};
    if (::mknod(full.c_str(), S_IFCHR | 0666, makedev(1, 7)) == 0 && ::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0) {
        // full: the write fails with the device's reason; it stays a device.
        auto r = run_sdfc("glsl " + q(s) + " -o " + q(full));
        CHECK(r.status == 1);
        CHECK(r.err.find("sdfc: error: cannot write '" + full + "': No space left on device") != std::string::npos);
        REQUIRE(::stat(full.c_str(), &st) == 0);
        CHECK(S_ISCHR(st.st_mode));
        r = run_sdfc("render " + q(s) + " -o " + q(full) + " --width 8 --height 8");
        CHECK(r.status == 2);
        CHECK(r.err.find("cannot write '" + full + "': no extension") != std::string::npos);
        REQUIRE(::stat(full.c_str(), &st) == 0);
        CHECK(S_ISCHR(st.st_mode));
        // null takes the text.
        CHECK(run_sdfc("glsl " + q(s) + " -o " + q(null)).status == 0);
        REQUIRE(::stat(null.c_str(), &st) == 0);
        CHECK(S_ISCHR(st.st_mode));
    } else {
        WARN("cannot make device nodes (not root?): the device cases are skipped");
    }
    test::RunResult r;

    // A FIFO: its reader gets the whole image.
    const std::string fifo = dir + "/pipe.png";
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    std::string got;
    std::thread reader([&] {
        std::ifstream in(fifo, std::ios::binary);
        got.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    });
    r = run_sdfc("render " + q(s) + " -o " + q(fifo) + " --width 24 --height 16 --quiet");
    int release = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);  // a reader still waiting (the write failed) ends
    if (release >= 0) ::close(release);
    reader.join();
    CHECK(r.status == 0);
    REQUIRE(::lstat(fifo.c_str(), &st) == 0);
    CHECK(S_ISFIFO(st.st_mode));
    const std::string copy = dir + "/copy.png";
    std::ofstream(copy, std::ios::binary) << got;
    CHECK(read_image(copy).width == 24);

    // A symlink stays a link; its target gets the new image.
    const std::string real = dir + "/real.png", link = dir + "/link.png";
    REQUIRE(run_sdfc("render " + q(s) + " -o " + q(real) + " --width 8 --height 8 --quiet").status == 0);
    fs::create_symlink("real.png", link);
    r = run_sdfc("render " + q(s) + " -o " + q(link) + " --width 20 --height 10 --quiet");
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::is_symlink(link));
    CHECK(read_image(real).width == 20);
    // A dangling link: its target is made.
    const std::string dangling = dir + "/dangling.png";
    fs::create_symlink("made.png", dangling);
    CHECK(run_sdfc("render " + q(s) + " -o " + q(dangling) + " --width 8 --height 8 --quiet").status == 0);
    CHECK(fs::is_symlink(dangling));
    CHECK(read_image(dir + "/made.png").width == 8);
    // A directory is refused before the work.
    fs::create_directories(dir + "/adir.png");
    r = run_sdfc("render " + q(s) + " -o " + q(dir + "/adir.png") + " --width 8 --height 8");
    CHECK(r.status == 1);
    CHECK(r.err.find("cannot write '" + dir + "/adir.png': Is a directory") != std::string::npos);
    CHECK(fs::is_directory(dir + "/adir.png"));
    CHECK(temps_in(dir) == "");
}

TEST_CASE("standard output that cannot be written is an error") {
    std::string s = test::write_temp("stdout.sdf", "sphere(1);\n");
    for (const std::string& args : {"glsl " + q(s), "eval " + q(s) + " --at 0,0,0", "compile " + q(s) + " --emit ir",
                                    "compile " + q(s) + " --emit ast", "compile " + q(s) + " --emit bytecode",
                                    "bench " + q(s) + " --width 8 --height 8 --repeat 1", std::string("--help"),
                                    std::string("--version"), std::string("render --help")}) {
        INFO(args);
        auto r = run_to(args, "/dev/full");
        CHECK(r.status == 1);
        CHECK(r.err == "sdfc: error: cannot write to standard output: No space left on device\n");
        // A closed standard output too.
        r = run_to(args, "&-");
        CHECK(r.status == 1);
        CHECK(r.err.find("sdfc: error: cannot write to standard output: ") == 0);
    }
    // A closed standard output that nothing is written to is no error (as for GNU tools).
    const std::string png = test::temp_dir() + "/closed_stdout.png";
    for (const std::string& args : {"check " + q(s), "render " + q(s) + " -o " + q(png) + " --width 8 --height 8",
                                    "glsl " + q(s) + " -o " + q(test::temp_dir() + "/closed_stdout.glsl")}) {
        INFO(args);
        auto r = run_to(args, "&-");
        CHECK(r.status == 0);
        CHECK(r.err.find("error") == std::string::npos);
    }
    CHECK(fs::exists(png));
}

TEST_CASE("an output that is the script or a file it imports is refused") {
    const std::string dir = fresh_dir("self");
    const std::string lib = dir + "/lib.sdf", main = dir + "/main.sdf";
    std::ofstream(lib) << "def ball(r) = sphere(r);\n";
    std::ofstream(main) << "import \"lib.sdf\";\nball(1);\n";
    const std::string lib_text = test::slurp(lib), main_text = test::slurp(main);
    fs::create_symlink("main.sdf", dir + "/alias.sdf");
    for (const std::string& args :
         {"glsl " + q(main) + " -o " + q(main), "glsl " + q(main) + " --target html -o " + q(main),
          "glsl " + q(main) + " -o " + q(dir + "/alias.sdf"), "glsl " + q(main) + " -o " + q(lib),
          "glsl " + q(main) + " --target html -o " + q(lib)}) {
        INFO(args);
        auto r = run_sdfc(args);
        CHECK(r.status == 1);
        CHECK(r.err.find("sdfc: error: cannot write '") == 0);
        CHECK((r.err.find("it is the scene file") != std::string::npos || r.err.find("the scene imports it") != std::string::npos));
    }
    CHECK(test::slurp(lib) == lib_text);
    CHECK(test::slurp(main) == main_text);
    CHECK(fs::is_symlink(dir + "/alias.sdf"));
    CHECK(temps_in(dir) == "");
}

TEST_CASE("SIGINT or SIGTERM during the write removes the temporary file and the old output stays") {
    const std::string dir = fresh_dir("signal");
    std::string s = test::write_temp("signal.sdf", kScene);
    const std::string out = dir + "/out.png";
    REQUIRE(run_sdfc("render " + q(s) + " -o " + q(out) + " --width 8 --height 8 --quiet").status == 0);
    const std::string before = test::slurp(out);
    std::string exe = std::getenv("SDFC_BIN") ? std::getenv("SDFC_BIN") : SDFC_BIN_PATH;
    for (int sig : {SIGINT, SIGTERM}) {
        INFO("signal " << sig);
        pid_t pid = ::fork();
        if (pid == 0) {
            ::setenv("SDFC_TEST_WRITE_DELAY_MS", "20000", 1);  // hold the temporary file open
            int null = ::open("/dev/null", O_WRONLY);
            ::dup2(null, 1);
            ::dup2(null, 2);
            ::execl(exe.c_str(), exe.c_str(), "render", s.c_str(), "-o", out.c_str(), "--width", "32", "--height", "32",
                    "--quiet", (char*)nullptr);
            ::_exit(127);
        }
        REQUIRE(pid > 0);
        bool seen = false;
        for (int i = 0; i < 20000 && !seen; ++i) {
            seen = !temps_in(dir).empty();
            if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        CHECK(seen);
        ::kill(pid, sig);
        int st = 0;
        REQUIRE(::waitpid(pid, &st, 0) == pid);
        CHECK(WIFSIGNALED(st));
        if (WIFSIGNALED(st)) CHECK(WTERMSIG(st) == sig);
        CHECK(temps_in(dir) == "");
        CHECK(test::slurp(out) == before);
    }
}

TEST_CASE("the output path and format are checked before the work naming the user's path and the reason") {
    const std::string dir = fresh_dir("precheck");
    // The script has an error: the output's error comes first, so nothing was compiled.
    std::string bad = test::write_temp("precheck_bad.sdf", "sphere(;\n");
    std::string s = test::write_temp("precheck.sdf", kScene);
    auto r = run_sdfc("render " + q(bad) + " -o " + q(dir + "/nosuch/x.png"));
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot write '" + dir + "/nosuch/x.png': folder '" + dir + "/nosuch': No such file or directory\n");
    r = run_sdfc("render " + q(bad) + " -o " + q(dir + "/x.foo"));
    CHECK(r.status == 2);  // a command-line mistake, as mesh's unknown format
    CHECK(r.err.find("sdfc: error: cannot write '" + dir + "/x.foo': unknown image format '.foo'") == 0);
    r = run_sdfc("slice " + q(bad) + " --axis z --at 0 -o " + q(dir + "/noext"));
    CHECK(r.status == 2);
    CHECK(r.err.find("sdfc: error: cannot write '" + dir + "/noext': no extension") == 0);
    r = run_sdfc("render " + q(bad) + " --frames 0:3 -o " + q(dir + "/nosuch/f{frame:04d}.png"));
    CHECK(r.status == 1);
    CHECK(r.err.find("cannot write '" + dir + "/nosuch/f0000.png'") != std::string::npos);
    r = run_sdfc("render " + q(bad) + " --aov depth -o " + q(dir + "/a.png"));
    CHECK(r.status == 1);  // the script's error: the outputs were fine
    CHECK(r.err.find("error:") != std::string::npos);
    r = run_sdfc("glsl " + q(bad) + " -o " + q(dir + "/nosuch/x.glsl"));
    CHECK(r.status == 1);
    CHECK(r.err.find("sdfc: error: cannot write '" + dir + "/nosuch/x.glsl': folder") == 0);
    // A folder that takes no new files (a read-only file system: root passes permission bits).
    const std::string ro = dir + "/ro";
    fs::create_directories(ro);
    if (mount_tmpfs(ro, 16, true)) {
        Unmount unmount{ro};
        r = run_sdfc("render " + q(s) + " -o " + q(ro + "/x.png") + " --width 8 --height 8");
        CHECK(r.status == 1);
        CHECK(r.err == "sdfc: error: cannot write '" + ro + "/x.png': folder '" + ro + "': Read-only file system\n");
    }
    CHECK(temps_in(dir) == "");
}

TEST_CASE("a legal output name of up to 255 bytes is written") {
    const std::string dir = fresh_dir("longname");
    std::string s = test::write_temp("longname.sdf", "sphere(1);\n");
    for (size_t stem : {249u, 251u}) {
        const std::string out = dir + "/" + std::string(stem, 'n') + ".png";
        auto r = run_sdfc("render " + q(s) + " -o " + q(out) + " --width 8 --height 8 --quiet");
        INFO(r.err);
        CHECK(r.status == 0);
        CHECK(read_image(out).width == 8);
        const std::string glsl = dir + "/" + std::string(stem, 'g') + ".txt";
        CHECK(run_sdfc("glsl " + q(s) + " -o " + q(glsl)).status == 0);
    }
    CHECK(temps_in(dir) == "");
}

TEST_CASE("eval --points is bounded and a device or directory or missing file or --at too is an error") {
    std::string s = test::write_temp("points.sdf", "sphere(1);\n");
    auto r = run_sdfc("eval " + q(s) + " --points /dev/zero --max-file-size 100000");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: '/dev/zero' is over the limit of 100000 bytes (raise it with --max-file-size)\n");
    r = run_sdfc("eval " + q(s) + " --points /dev/zero");  // the default limit
    CHECK(r.status == 1);
    CHECK(r.err.find("over the limit") != std::string::npos);
    r = run_sdfc("eval " + q(s) + " --points " + q(test::temp_dir()));
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: cannot read '" + test::temp_dir() + "': Is a directory\n");
    r = run_sdfc("eval " + q(s) + " --points " + q(test::temp_dir() + "/no-such-points"));
    CHECK(r.status == 1);
    CHECK(r.err.find("No such file or directory") != std::string::npos);
    std::string pts = test::write_temp("points.txt", "0 0 0\n2 0 0\n");
    r = run_sdfc("eval " + q(s) + " --points " + q(pts));
    CHECK(r.status == 0);
    CHECK(r.out == "-1\n1\n");
    r = run_sdfc("eval " + q(s) + " --at 0,0,0 --points " + q(test::temp_dir() + "/no-such-points"));
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: eval takes --at X,Y,Z or --points FILE, not both\n");
}

TEST_CASE("every image format writes a file that reads back") {
    // Found by tests/fuzz/fuzz_output.cpp: this OpenImageIO's TIFF writer through an
    // in-memory proxy wrote a file without its image length.
    const std::string dir = fresh_dir("formats");
    std::string s = test::write_temp("formats.sdf", kScene);
    for (const char* ext : {"png", "jpg", "exr", "hdr", "tif", "tiff", "bmp", "tga", "webp", "ppm", "sgi"}) {
        INFO(ext);
        const std::string out = dir + "/out." + ext;
        auto r = run_sdfc("render " + q(s) + " -o " + q(out) + " --width 40 --height 24 --quiet");
        CHECK(r.status == 0);
        Image img = read_image(out);
        CHECK(img.width == 40);
        CHECK(img.height == 24);
    }
    CHECK(temps_in(dir) == "");
}
