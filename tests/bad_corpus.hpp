// The bad-script corpus, tests/bad/*.sdf: each file is a script with one mistake, and its
// first line states the first line of the diagnostics it must give:
//     // expect: bad/NAME.sdf:LINE:COL: error: MESSAGE
// An optional second line sets limits with sdfc's flags:
//     // args: --max-shapes 100
// Paths in diagnostics are shown relative to tests/ (any mention of the folder is
// replaced), so expectations do not depend on where the checkout is. Every .sdf file
// directly in tests/bad/ is a case (helpers that cases import live in tests/bad/lib/):
// adding a case is adding a file. Run by tests/lang/test_bad_scripts.cpp (the library)
// and tests/cli/test_bad_scripts.cpp (`sdfc check`).
#pragma once
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "lang/interpreter.hpp"

namespace sdfc::test {

struct BadCase {
    std::string path;  // absolute
    std::string name;  // file name
    std::string expect;
    std::vector<std::string> args;
};

inline std::string tests_dir() { return std::string(SDFC_SOURCE_DIR) + "/tests/"; }

// Diagnostics with the tests folder removed from every path.
inline std::string relative_paths(std::string text) {
    const std::string dir = tests_dir();
    for (size_t p; (p = text.find(dir)) != std::string::npos;) text.erase(p, dir.size());
    return text;
}

inline std::vector<BadCase> bad_cases() {
    std::vector<BadCase> out;
    for (const auto& e : std::filesystem::directory_iterator(tests_dir() + "bad")) {
        if (!e.is_regular_file() || e.path().extension() != ".sdf") continue;
        BadCase c;
        c.path = e.path().string();
        c.name = e.path().filename().string();
        std::ifstream in(c.path, std::ios::binary);
        std::string line;
        std::getline(in, line);
        const std::string tag = "// expect: ";
        if (line.rfind(tag, 0) != 0) throw std::runtime_error(c.name + ": the first line must be `" + tag + "...`");
        c.expect = line.substr(tag.size());
        if (std::getline(in, line) && line.rfind("// args:", 0) == 0) {
            std::istringstream ss(line.substr(8));
            for (std::string w; ss >> w;) c.args.push_back(w);
        }
        out.push_back(std::move(c));
    }
    std::sort(out.begin(), out.end(), [](const BadCase& a, const BadCase& b) { return a.name < b.name; });
    return out;
}

// The limit flags of `// args:` as the Limits the sdfc command would use.
inline Limits limits_from(const std::vector<std::string>& args) {
    Limits l;
    for (size_t i = 0; i + 1 < args.size(); i += 2) {
        const std::string& f = args[i];
        const long v = std::stol(args[i + 1]);
        if (f == "--max-recursion") l.max_recursion = int(v);
        else if (f == "--max-calls") l.max_calls = size_t(v);
        else if (f == "--max-iterations") l.max_loop_iterations = v;
        else if (f == "--max-shapes") l.max_shapes = size_t(v);
        else if (f == "--max-shape-depth") l.max_shape_depth = int(v);
        else if (f == "--max-ops") l.max_ops = size_t(v);
        else if (f == "--max-nesting") l.max_nesting = int(v);
        else if (f == "--max-file-size") l.max_file_bytes = size_t(v);
        else throw std::runtime_error("unknown flag in // args: " + f);
    }
    if (args.size() % 2) throw std::runtime_error("// args: takes flag-value pairs");
    return l;
}

}  // namespace sdfc::test
