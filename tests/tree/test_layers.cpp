// The source tree's own rules, read from the files: includes point down the layers (the
// table below is docs/architecture.md's drawing), no source file over 700 lines, and no
// shader or page text held as a long string literal inside C++ (it lives in .glsl/.html/.js
// files that the build embeds).
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// Each layer's folder and the layers it may include (itself always).
struct Layer {
    const char* dir;
    std::vector<const char*> below;
};
const std::vector<Layer>& layers() {
    static const std::vector<Layer> table = {
        {"compiler/base", {}},
        {"compiler/ir", {"compiler/base"}},
        {"compiler/scene", {"compiler/ir", "compiler/base"}},
        {"grammar", {}},
        {"lang", {"grammar", "compiler/scene", "compiler/ir", "compiler/base"}},
        {"compiler/bytecode", {"compiler/scene", "compiler/ir", "compiler/base"}},
        {"compiler/render", {"compiler/bytecode", "compiler/scene", "compiler/ir", "compiler/base"}},
        {"compiler/glsl", {"compiler/render", "compiler/bytecode", "compiler/scene", "compiler/ir", "compiler/base"}},
        {"runtime/eval", {"compiler/bytecode", "compiler/scene", "compiler/ir", "compiler/base"}},
        {"runtime/io", {"compiler/render", "compiler/base"}},  // (rules.h's sRGB encoding only)
        {"runtime/io/oiio", {"runtime/io", "compiler/render", "compiler/base"}},  // the image module
        {"runtime/cpu",
         {"runtime/eval", "runtime/io", "compiler/render", "compiler/bytecode", "compiler/scene", "compiler/ir",
          "compiler/base"}},
        {"runtime/mesh", {"runtime/eval", "runtime/io", "compiler/bytecode", "compiler/scene", "compiler/ir", "compiler/base"}},
        // The public API (libsdfc.so) over every stage, as the command is.
        {"runtime/api",
         {"runtime/cpu", "runtime/mesh", "runtime/eval", "runtime/io", "compiler/glsl", "lang", "compiler/render",
          "compiler/bytecode", "compiler/scene", "compiler/ir", "compiler/base"}},
    };
    return table;
}

const fs::path kRoot = SDFC_SOURCE_DIR;

std::string folder_of(const std::string& rel) { return fs::path(rel).parent_path().generic_string(); }

const Layer* layer_of(const std::string& folder) {
    for (const Layer& l : layers())
        if (folder == l.dir) return &l;
    return nullptr;
}

std::vector<std::string> source_files() {
    std::vector<std::string> out;
    for (const char* top : {"compiler", "lang", "grammar", "runtime", "cli", "bench", "tests"}) {
        if (!fs::exists(kRoot / top)) continue;
        for (const auto& e : fs::recursive_directory_iterator(kRoot / top)) {
            if (!e.is_regular_file()) continue;
            const std::string ext = e.path().extension().string();
            if (ext == ".cpp" || ext == ".hpp" || ext == ".h" || ext == ".def" || ext == ".inl" || ext == ".glsl" || ext == ".html" ||
                ext == ".js")
                out.push_back(fs::relative(e.path(), kRoot).generic_string());
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::string> lines_of(const std::string& rel) {
    std::ifstream in(kRoot / rel);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

bool is_cxx(const std::string& rel) {
    const std::string ext = fs::path(rel).extension().string();
    return ext == ".cpp" || ext == ".hpp" || ext == ".h" || ext == ".def" || ext == ".inl";
}

}  // namespace

TEST_CASE("every layer folder exists and holds sources", "[tree]") {
    for (const Layer& l : layers()) {
        INFO(l.dir);
        CHECK(fs::is_directory(kRoot / l.dir));
    }
}

TEST_CASE("includes point down the layers, never up or sideways", "[tree]") {
    const std::regex include_re(R"re(^\s*#\s*include\s+"([^"]+)")re");
    std::vector<std::string> bad;
    size_t checked = 0;
    for (const std::string& rel : source_files()) {
        const Layer* from = layer_of(folder_of(rel));
        if (!from || !is_cxx(rel)) continue;  // cli/, bench/, tests/ sit on top of everything
        for (const std::string& line : lines_of(rel)) {
            std::smatch m;
            if (!std::regex_search(line, m, include_re)) continue;
            const std::string target = m[1];
            if (target.find('/') == std::string::npos) continue;  // generated or same-folder files
            const std::string to = folder_of(target);
            ++checked;
            bool ok = to == from->dir;
            for (const char* b : from->below) ok = ok || to == b;
            if (!ok) bad.push_back(rel + " includes " + target);
        }
    }
    for (const std::string& b : bad) UNSCOPED_INFO(b);
    CHECK(bad.empty());
    CHECK(checked > 50);
}

TEST_CASE("only the image module includes OpenImageIO (start-up without its libraries)", "[tree]") {
    for (const std::string& rel : source_files()) {
        if (!is_cxx(rel) || rel.rfind("runtime/io/oiio/", 0) == 0 || rel.rfind("tests/", 0) == 0) continue;
        for (const std::string& line : lines_of(rel)) {
            INFO(rel << ": " << line);
            CHECK(line.find("#include <OpenImageIO/") == std::string::npos);
        }
    }
}

TEST_CASE("only the preview server includes cpp-httplib (start-up without its libraries)", "[tree]") {
    for (const std::string& rel : source_files()) {
        if (!is_cxx(rel) || rel == "cli/preview/server.cpp" || rel.rfind("tests/", 0) == 0) continue;
        for (const std::string& line : lines_of(rel)) {
            INFO(rel << ": " << line);
            CHECK(line.find("#include <httplib.h>") == std::string::npos);
        }
    }
}

TEST_CASE("the public header includes nothing of sdfc's or of its dependencies", "[tree]") {
    const std::regex include_re(R"re(^\s*#\s*include\s+[<"]([^>"]+)[>"])re");
    for (const std::string& line : lines_of("runtime/api/sdfc.hpp")) {
        std::smatch m;
        if (!std::regex_search(line, m, include_re)) continue;
        INFO(line);
        CHECK(std::string(m[1]).find_first_of("./") == std::string::npos);  // <string>, <vector>: the standard library
    }
}

TEST_CASE("no source file is over 700 lines", "[tree]") {
    std::vector<std::string> long_files;
    for (const std::string& rel : source_files())
        if (lines_of(rel).size() > 700) long_files.push_back(rel + ": " + std::to_string(lines_of(rel).size()) + " lines");
    for (const std::string& f : long_files) UNSCOPED_INFO(f);
    CHECK(long_files.empty());
}

TEST_CASE("no raw string literal over 40 lines inside C++", "[tree]") {
    // Shader and page text lives in .glsl/.html/.js files that the build embeds.
    std::vector<std::string> bad;
    const std::regex open_re(R"re(R"([A-Za-z_]{0,16})\()re");
    for (const std::string& rel : source_files()) {
        if (!is_cxx(rel)) continue;
        const auto lines = lines_of(rel);
        for (size_t i = 0; i < lines.size(); ++i) {
            std::smatch m;
            if (!std::regex_search(lines[i], m, open_re)) continue;
            const std::string close = ")" + m[1].str() + "\"";
            const std::string rest = m.suffix();
            if (rest.find(close) != std::string::npos) continue;  // closes on the same line
            size_t j = i + 1;
            while (j < lines.size() && lines[j].find(close) == std::string::npos) ++j;
            if (j - i + 1 > 40) bad.push_back(rel + ":" + std::to_string(i + 1) + ": " + std::to_string(j - i + 1) + " lines");
            i = j;
        }
    }
    for (const std::string& b : bad) UNSCOPED_INFO(b);
    CHECK(bad.empty());
}

TEST_CASE("no test name holds a semicolon or starts with a dash (ctest's command line would run nothing)", "[tree]") {
    const std::regex name_re(R"re((TEST_CASE|TEMPLATE_TEST_CASE|SCENARIO)\s*\(\s*"([^"]*)")re");
    std::vector<std::string> bad;
    for (const std::string& rel : source_files()) {
        if (rel.rfind("tests/", 0) != 0 || !is_cxx(rel)) continue;
        const auto lines = lines_of(rel);
        for (size_t i = 0; i < lines.size(); ++i) {
            std::smatch m;
            // A name starting with '-' reaches Catch as an option: it prints its usage, passes.
            if (std::regex_search(lines[i], m, name_re) && (m[2].str().find(';') != std::string::npos || m[2].str().rfind("-", 0) == 0))
                bad.push_back(rel + ":" + std::to_string(i + 1) + ": " + m[2].str());
        }
    }
    for (const std::string& b : bad) UNSCOPED_INFO(b);
    CHECK(bad.empty());
}
