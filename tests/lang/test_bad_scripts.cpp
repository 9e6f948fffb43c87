// The bad-script corpus through the library: load, interpret and compile each file of
// tests/bad/ and compare the first line of the diagnostics (see tests/bad_corpus.hpp).
#include <catch2/catch.hpp>

#include "bad_corpus.hpp"
#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"

using namespace sdfc;

TEST_CASE("every script of tests/bad gives its expected first error") {
    const auto cases = test::bad_cases();
    CHECK(cases.size() >= 40);
    for (const auto& c : cases) {
        DYNAMIC_SECTION(c.name) {
            InterpretOptions opts;
            opts.limits = test::limits_from(c.args);
            std::string got;
            try {
                SourceManager sm;
                Scene s = load_scene(sm, c.path, opts);
                compile_scene(s);
            } catch (const CompileError& e) {
                got = test::relative_paths(e.formatted());
            }
            INFO(got);
            REQUIRE(!got.empty());
            CHECK(got.substr(0, got.find('\n')) == c.expect);
            // Then the source line and a caret under the column.
            size_t l1 = got.find('\n'), l2 = got.find('\n', l1 + 1), l3 = got.find('\n', l2 + 1);
            REQUIRE(l3 != std::string::npos);
            CHECK(got.substr(l2 + 1, l3 - l2 - 1).find_first_not_of(" \t") == l3 - l2 - 2);
            CHECK(got[l3 - 1] == '^');
        }
    }
}
