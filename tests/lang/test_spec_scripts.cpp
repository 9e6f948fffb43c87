// Every script printed in LANGUAGE.md compiles (the contract's own examples). Read from
// ../shared/spec; skipped when the shared folder is absent.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "compiler/bytecode/compile.hpp"
#include "lang/interpreter.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

TEST_CASE("every script block of LANGUAGE.md compiles") {
    fs::path spec = fs::path(SDFC_SHARED_DIR) / "spec" / "LANGUAGE.md";
    if (!fs::exists(spec)) {
        WARN("skipped: " << spec << " is absent");
        return;
    }
    std::ifstream in(spec);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    // Code blocks; the one describing the command line is not a script.
    std::vector<std::string> blocks;
    for (size_t p = 0; (p = text.find("```", p)) != std::string::npos;) {
        size_t start = text.find('\n', p) + 1;
        size_t end = text.find("```", start);
        if (end == std::string::npos) break;
        std::string b = text.substr(start, end - start);
        if (b.find("sdfc render") == std::string::npos) blocks.push_back(b);
        p = end + 3;
    }
    REQUIRE(blocks.size() >= 3);
    // Section 4 imports "lib/furniture.sdf": give it one.
    fs::path dir = fs::temp_directory_path() / "sdfc-spec-scripts";
    fs::create_directories(dir / "lib");
    std::ofstream(dir / "lib" / "furniture.sdf") << "def chair() = box([0.5, 1, 0.5]);\n";
    for (size_t i = 0; i < blocks.size(); ++i) {
        fs::path file = dir / ("block" + std::to_string(i) + ".sdf");
        std::ofstream(file) << blocks[i];
        INFO("LANGUAGE.md code block " << i << ":\n" << blocks[i]);
        SourceManager sm;
        try {
            Scene s = interpret_file(sm, file.string());
            CompiledScene cs = compile_scene(s);
            CHECK(!cs.distance.code.empty());
        } catch (const CompileError& e) {
            FAIL(e.formatted());
        }
    }
}
