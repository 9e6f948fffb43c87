// The editor grammar (grammar/sdf.tmLanguage.json) names every built-in of the language,
// and nothing else, as a support.function: its lists are checked against the tables
// (lang/builtins.def, compiler/scene/shapes.def) so a new shape cannot be left out.
#include <catch2/catch.hpp>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "lang/interp.hpp"

TEST_CASE("the TextMate grammar's built-in names are the language's") {
    std::ifstream in(std::string(SDFC_SOURCE_DIR) + "/grammar/sdf.tmLanguage.json");
    REQUIRE(in);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    // "name": "support.function....", "match": "\\b(a|b|c)\\b(?=\\s*\\()"
    const std::regex rule(R"re("name": "support\.function\.[a-z.]+sdf",\s*"match": "\\\\b\(([a-z_0-9|]+)\)\\\\b)re");
    std::set<std::string> in_grammar;
    int lists = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), rule); it != std::sregex_iterator(); ++it) {
        ++lists;
        std::stringstream names((*it)[1].str());
        for (std::string n; std::getline(names, n, '|');) CHECK(in_grammar.insert(n).second);  // each once
    }
    CHECK(lists == 6);
    const std::set<std::string> language(sdfc::builtin_names().begin(), sdfc::builtin_names().end());
    for (const std::string& n : language) {
        INFO("a built-in the grammar does not know: " << n);
        CHECK(in_grammar.count(n) == 1);
    }
    for (const std::string& n : in_grammar) {
        INFO("a name in the grammar that is no built-in: " << n);
        CHECK(language.count(n) == 1);
    }
}
