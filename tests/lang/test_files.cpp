// Source files: imports relative to the importing file, each file read once, cycles; what
// a file may be (a regular file, within the size limit) and contain (UTF-8 text without
// NUL bytes). Every problem is a located diagnostic (LANGUAGE.md sections 2, 4 and 9).
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "support.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {

// A fresh folder of script files, removed afterwards. Diagnostics are read with the
// folder's path replaced by "DIR".
struct Folder {
    fs::path root;
    Folder() {
        static int n = 0;
        root = fs::temp_directory_path() / ("sdfc-files-" + std::to_string(::getpid()) + "-" + std::to_string(n++));
        fs::remove_all(root);
        fs::create_directories(root);
    }
    ~Folder() { fs::remove_all(root); }
    std::string write(const std::string& rel, const std::string& text) const {
        fs::path p = root / rel;
        fs::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << text;
        return p.string();
    }
    std::string path(const std::string& rel) const { return (root / rel).string(); }
    // The diagnostics of loading and compiling `rel`, or "".
    std::string errors(const std::string& rel, Limits limits = {}) const {
        InterpretOptions o;
        o.limits = limits;
        std::string out;
        try {
            SourceManager sm;
            Scene s = load_scene(sm, path(rel), o);
            compile_scene(s);
        } catch (const CompileError& e) {
            out = e.formatted();
        }
        const std::string dir = root.string();
        for (size_t p; (p = out.find(dir)) != std::string::npos;) out.replace(p, dir.size(), "DIR");
        return out;
    }
    std::string first_error(const std::string& rel, Limits limits = {}) const {
        std::string e = errors(rel, limits);
        return e.substr(0, e.find('\n'));
    }
    float dist(const std::string& rel, float x, float y, float z) const {
        SourceManager sm;
        Scene s = load_scene(sm, path(rel));
        return test::dist(compile_scene(s), x, y, z);
    }
};

size_t count(const std::string& s, const std::string& part) {
    size_t n = 0;
    for (size_t p = s.find(part); p != std::string::npos; p = s.find(part, p + 1)) ++n;
    return n;
}

}  // namespace

TEST_CASE("imports are relative to the importing file, whatever the working folder") {
    Folder d;
    d.write("scenes/main.sdf", "import \"../lib/a.sdf\";\nball();\n");
    d.write("lib/a.sdf", "import \"parts/b.sdf\";\ndef ball() = sphere(rb());\n");
    d.write("lib/parts/b.sdf", "def rb() = 0.5;\nsphere(99);  // shapes and settings of an imported file are ignored\n");
    CHECK(d.errors("scenes/main.sdf") == "");
    CHECK(d.dist("scenes/main.sdf", 0, 0, 0) == Approx(-0.5f));
    // The same file by two paths, and by two importers: one file, no redefinition.
    d.write("scenes/two.sdf", "import \"../lib/parts/b.sdf\";\nimport \"../lib/../lib/parts/b.sdf\";\nimport \"../lib/a.sdf\";\n"
                              "translate([rb(), 0, 0]) ball();\n");
    CHECK(d.errors("scenes/two.sdf") == "");
    CHECK(d.dist("scenes/two.sdf", 0.5f, 0, 0) == Approx(-0.5f));
}

TEST_CASE("an error in an imported file is reported once, where it is") {
    Folder d;
    d.write("main.sdf", "import \"lib.sdf\";\nimport \"lib.sdf\";\nsphere(1);\n");
    d.write("lib.sdf", "def ok() = 1;\nlet bad = 1 / 0;\n");
    std::string e = d.errors("main.sdf");
    CHECK(e.rfind("DIR/lib.sdf:2:13: error: division by zero\n", 0) == 0);
    CHECK(count(e, "error:") == 1);
}

TEST_CASE("a let both defined and imported is an error in either order, but a library imported twice is not") {
    Folder d;
    d.write("lib.sdf", "let R = 0.5;\ndef ball() = sphere(R);\n");
    d.write("let_first.sdf", "let R = 1;\nimport \"lib.sdf\";\nsphere(R);\n");
    CHECK(d.first_error("let_first.sdf") ==
          "DIR/let_first.sdf:2:1: error: this import defines 'R' (DIR/lib.sdf:1), which is already defined in this scope (at line 1)");
    d.write("import_first.sdf", "import \"lib.sdf\";\nlet R = 1;\nsphere(R);\n");
    CHECK(d.first_error("import_first.sdf") == "DIR/import_first.sdf:2:5: error: 'R' is already defined in this scope (at DIR/lib.sdf:1)");
    // A diamond: main and big.sdf both import lib.sdf; its names arrive twice, the same.
    d.write("big.sdf", "import \"lib.sdf\";\ndef big() = scale(2) ball();\n");
    d.write("diamond.sdf", "import \"lib.sdf\";\nimport \"big.sdf\";\nball();\nbig();\n");
    CHECK(d.errors("diamond.sdf").empty());
    // A def of the importing file takes the place of the library's; of two libraries, the
    // first import's R wins.
    d.write("own_ball.sdf", "import \"lib.sdf\";\ndef ball() = box(1);\nball();\n");
    CHECK(d.errors("own_ball.sdf").empty());
    d.write("lib2.sdf", "let R = 2;\n");
    d.write("two_libs.sdf", "import \"lib.sdf\";\nimport \"lib2.sdf\";\nsphere(R);\n");
    CHECK(d.errors("two_libs.sdf").empty());
}

TEST_CASE("managers sharing a snapshot read each file once: the frames of a batch see one version of a script") {
    Folder d;
    d.write("lib.sdf", "def r() = 1;\n");
    const std::string main = d.write("main.sdf", "import \"lib.sdf\";\nsphere(r());\n");
    auto snapshot = std::make_shared<SourceSnapshot>();
    auto dist = [&](SourceManager& sm) { return test::dist(compile_scene(load_scene(sm, main)), 0, 0, 0); };
    SourceManager first(snapshot);
    CHECK(dist(first) == Approx(-1));
    d.write("lib.sdf", "def r() = 2;\n");  // saved during the batch
    SourceManager later(snapshot);
    CHECK(dist(later) == Approx(-1));
    CHECK(later.paths() == std::vector<std::string>{main, d.path("lib.sdf")});
    SourceManager alone;  // (a new run reads the file again)
    CHECK(dist(alone) == Approx(-2));
}

TEST_CASE("import cycles are errors at the import that closes them") {
    Folder d;
    d.write("a.sdf", "import \"b.sdf\";\nsphere(1);\n");
    d.write("b.sdf", "// b\nimport \"a.sdf\";\ndef f() = 1;\n");
    CHECK(d.first_error("a.sdf") == "DIR/b.sdf:2:1: error: import cycle: a.sdf -> b.sdf -> a.sdf");
    d.write("self.sdf", "import \"self.sdf\";\n");
    CHECK(d.first_error("self.sdf") == "DIR/self.sdf:1:1: error: import cycle: self.sdf -> self.sdf");
    d.write("x/c.sdf", "import \"../y/d.sdf\";\n");
    d.write("y/d.sdf", "import \"e.sdf\";\n");
    d.write("y/e.sdf", "\n\nimport \"../x/c.sdf\";\n");
    CHECK(d.first_error("x/c.sdf") == "DIR/y/e.sdf:3:1: error: import cycle: c.sdf -> d.sdf -> e.sdf -> c.sdf");
    // The names the failed import would have brought are not reported again as unknown.
    d.write("p.sdf", "import \"q.sdf\";\ndef fp() = 1;\nsphere(fq());\n");
    d.write("q.sdf", "import \"p.sdf\";\ndef fq() = 1;\n");
    const std::string e = d.errors("p.sdf");
    CHECK(e.find("DIR/q.sdf:1:1: error: import cycle: p.sdf -> q.sdf -> p.sdf") == 0);
    CHECK(e.find("unknown name") == std::string::npos);
}

TEST_CASE("missing, directory, FIFO and oversized files are located errors") {
    Folder d;
    d.write("main.sdf", "sphere(1);\nimport \"nothere.sdf\";\n");
    CHECK(d.first_error("main.sdf") == "DIR/main.sdf:2:1: error: cannot open 'DIR/nothere.sdf': No such file or directory");
    fs::create_directories(d.root / "sub");
    d.write("dir.sdf", "import \"sub\";\n");
    CHECK(d.first_error("dir.sdf") == "DIR/dir.sdf:1:1: error: cannot read 'DIR/sub': not a regular file");
    // Opening a FIFO for reading would wait for a writer forever.
    REQUIRE(::mkfifo(d.path("pipe.sdf").c_str(), 0600) == 0);
    d.write("fifo.sdf", "import \"pipe.sdf\";\n");
    CHECK(d.first_error("fifo.sdf") == "DIR/fifo.sdf:1:1: error: cannot read 'DIR/pipe.sdf': not a regular file");
    CHECK(d.first_error("pipe.sdf") == "sdfc: error: cannot read 'DIR/pipe.sdf': not a regular file");
    d.write("big.sdf", "// " + std::string(200, 'x') + "\nsphere(1);\n");
    d.write("imports_big.sdf", "import \"big.sdf\";\n");
    Limits l;
    l.max_file_bytes = 100;
    CHECK(d.first_error("imports_big.sdf", l) ==
          "DIR/imports_big.sdf:1:1: error: 'DIR/big.sdf' is 215 bytes, over the limit of 100 bytes (--max-file-size)");
    CHECK(d.first_error("big.sdf", l) == "sdfc: error: 'DIR/big.sdf' is 215 bytes, over the limit of 100 bytes (--max-file-size)");
}

TEST_CASE("an unreadable file is an error") {
    Folder d;
    std::string p = d.write("secret.sdf", "sphere(1);\n");
    REQUIRE(::chmod(p.c_str(), 0) == 0);
    if (std::ifstream(p).good()) {
        WARN("skipped: running with permission to read any file (root)");
        return;
    }
    d.write("main.sdf", "import \"secret.sdf\";\n");
    CHECK(d.first_error("main.sdf") == "DIR/main.sdf:1:1: error: cannot open 'DIR/secret.sdf': Permission denied");
}

TEST_CASE("a symlink loop is an error with the OS reason, at the import") {
    Folder d;
    fs::create_symlink("b.sdf", d.path("a.sdf"));
    fs::create_symlink("a.sdf", d.path("b.sdf"));
    d.write("main.sdf", "sphere(1);\nimport \"a.sdf\";\n");
    CHECK(d.first_error("main.sdf") == "DIR/main.sdf:2:1: error: cannot open 'DIR/a.sdf': Too many levels of symbolic links");
    CHECK(d.first_error("a.sdf") == "sdfc: error: cannot open 'DIR/a.sdf': Too many levels of symbolic links");
}

TEST_CASE("binary files and invalid UTF-8 are errors at the offending byte") {
    Folder d;
    d.write("nul.sdf", std::string("sphere(1);\nbox(\0);\n", 18));
    CHECK(d.first_error("nul.sdf") == "DIR/nul.sdf:2:5: error: binary file: NUL byte in source text");
    d.write("imports_nul.sdf", "import \"nul.sdf\";\n");
    CHECK(d.first_error("imports_nul.sdf") == "DIR/nul.sdf:2:5: error: binary file: NUL byte in source text");
    const std::vector<std::pair<std::string, std::string>> bad{
        {"latin1", "let x = 1; // \xe9t\xe9\n"},        // Latin-1 bytes
        {"lone", "let x = 1; // \x80\n"},               // a continuation byte alone
        {"overlong", "let x = 1; // \xc0\xaf\n"},       // '/' in two bytes
        {"surrogate", "let x = 1; // \xed\xa0\x80\n"},  // U+D800
        {"too_big", "let x = 1; // \xf4\x90\x80\x80\n"},  // above U+10FFFF
        {"truncated", "let x = 1; // \xe2\x82"},        // cut off at the end of the file
    };
    for (const auto& [name, text] : bad) {
        INFO(name);
        d.write(name + ".sdf", text);
        CHECK(d.first_error(name + ".sdf") == "DIR/" + name + ".sdf:1:15: error: invalid UTF-8 in source text");
    }
    // Well-formed UTF-8 in comments and strings, a byte-order mark, CRLF lines: fine.
    d.write("good.sdf", "\xef\xbb\xbf// caf\xc3\xa9 \xe2\x9c\x93 \xf0\x9f\x8e\x89\r\nlet s = \"\xc3\xa9\";\r\nsphere(1);\r\n");
    CHECK(d.errors("good.sdf") == "");
    // Lone CRs (classic Mac OS) end lines too: a // comment stops there, errors count them.
    d.write("mac.sdf", "let a = 1;\r// note\rsphere(a);\rbox(;\r");
    CHECK(d.first_error("mac.sdf") == "DIR/mac.sdf:4:5: error: expected ')'");
    CHECK(d.errors("mac.sdf").find("\nbox(;\n    ^") != std::string::npos);
    // A non-ASCII character in code is a syntax error naming it.
    d.write("name.sdf", "let caf\xc3\xa9 = 1;\n");
    CHECK(d.first_error("name.sdf") == "DIR/name.sdf:1:8: error: unexpected character '\xc3\xa9'");
}

TEST_CASE("a very long line is quoted as a window around the column") {
    std::string src = "sphere(1);" + std::string(5000, ' ') + "sphere(-1);" + std::string(5000, ' ') + "\n";
    std::string e = test::error_of(src);
    CHECK(e.rfind("test.sdf:1:5018: error: argument 'r' of sphere must be zero or positive, not -1\n", 0) == 0);
    CHECK(e.size() < 600);
    size_t l1 = e.find('\n'), l2 = e.find('\n', l1 + 1);
    std::string line = e.substr(l1 + 1, l2 - l1 - 1), caret = e.substr(l2 + 1);
    CHECK(line.rfind("...", 0) == 0);
    CHECK(line.size() > 3);
    CHECK(line.substr(line.size() - 3) == "...");
    // The caret is under the '-' of "-1".
    CHECK(line[caret.find('^')] == '-');
}
