// The help pages, the man page and the shell completions (issue 15): all made from the one
// option table (cli/options.cpp), so each is checked for what a user reads or gets offered.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <regex>
#include <string>
#include <vector>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

// The line of `help` that describes `spec` ("  --width W"), and the lines that continue it.
std::string entry(const std::string& help, const std::string& spec) {
    size_t at = help.find("\n  " + spec + " ");
    if (at == std::string::npos) at = help.find("\n  " + spec + "\n");
    if (at == std::string::npos) return "";
    size_t end = at + 1;
    do end = help.find('\n', end + 1);
    while (end != std::string::npos && help.compare(end + 1, 4, "    ") == 0);
    return help.substr(at + 1, end - at - 1);
}

// What bash completes for `line` (its last word the one being typed; a final space: a new
// word), the script sourced as ~/.bashrc would.
std::string complete_bash(const std::string& script, const std::string& line) {
    const std::string sh = test::write_temp("completion.bash", script);
    const bool fresh = !line.empty() && line.back() == ' ';
    const std::string driver = test::write_temp("complete.sh", "source " + q(sh) + "\nCOMP_WORDS=(" + line + (fresh ? "''" : "") +
                                                                   ")\nCOMP_CWORD=$((${#COMP_WORDS[@]} - 1))\n_sdfc\necho \"${COMPREPLY[*]}\"\n");
    const std::string out = test::temp_dir() + "/completion.txt";
    REQUIRE(std::system(("bash " + q(driver) + " >" + q(out) + " 2>&1").c_str()) == 0);
    std::string r = test::slurp(out);
    while (!r.empty() && r.back() == '\n') r.pop_back();
    return r;
}

}  // namespace

TEST_CASE("every command's --help lists its options with their defaults") {
    const auto top = run_sdfc("--help");
    REQUIRE(top.status == 0);
    std::vector<std::string> cmds;
    const std::regex line("\n  sdfc ([a-z]+) ");
    for (auto it = std::sregex_iterator(top.out.begin(), top.out.end(), line); it != std::sregex_iterator(); ++it)
        cmds.push_back((*it)[1]);
    CHECK(cmds == std::vector<std::string>{"render", "glsl", "compile", "check", "eval", "slice", "mesh", "merge", "bench", "watch", "preview", "help"});
    for (const std::string& c : cmds) {
        INFO(c);
        const auto h = run_sdfc(c + " --help");
        CHECK(h.status == 0);
        CHECK(h.out.rfind("usage: sdfc " + c + " ", 0) == 0);
        CHECK(run_sdfc("help " + c).out == h.out);
        CHECK(run_sdfc(c + " -h").out == h.out);
    }
    const std::string render = run_sdfc("render --help").out;
    CHECK(entry(render, "--width W") == "  --width W                   picture width in pixels (default: 640)");
    CHECK(entry(render, "--max-steps N") == "  --max-steps N               sphere-tracing steps per ray (default: 256)");
    CHECK(entry(render, "--tonemap none|reinhard|aces") ==
          "  --tonemap none|reinhard|aces\n                              tone mapping; none clips at 1 (default: none)");
    CHECK(entry(render, "--max-recursion N") == "  --max-recursion N           nested def calls (default: 64)");
    CHECK(entry(render, "-o, --output OUT").find("{frame:04d}") != std::string::npos);
    const std::string mesh = run_sdfc("mesh --help").out;
    CHECK(entry(mesh, "--resolution N") == "  --resolution N              cells along the longest side of the box (default: 256)");
    CHECK(entry(run_sdfc("preview --help").out, "--port N").find("(default: 8421)") != std::string::npos);
    CHECK(entry(run_sdfc("watch --help").out, "--debounce MS").find("(default: 100)") != std::string::npos);
    CHECK(entry(run_sdfc("slice --help").out, "--width W").find("(default: 800)") != std::string::npos);
    // Commands without scene options do not list them.
    CHECK(run_sdfc("watch --help").out.find("--max-recursion") == std::string::npos);
}

TEST_CASE("help's errors") {
    auto r = run_sdfc("help nope");
    CHECK(r.status == 2);
    CHECK(r.err == "sdfc: error: help: no command 'nope' (see sdfc --help)\n");
    CHECK(run_sdfc("help --completion fish").err == "sdfc: error: --completion takes bash or zsh, not 'fish'\n");
    CHECK(run_sdfc("help --man render").err == "sdfc: error: help takes one of CMD, --man or --completion SHELL\n");
    CHECK(run_sdfc("help --mna").err == "sdfc: error: unknown option '--mna' (did you mean `--man`?)\n");
}

TEST_CASE("the man page documents every command and option") {
    const auto man = run_sdfc("help --man");
    REQUIRE(man.status == 0);
    CHECK(man.out.find(".TH SDFC 1 ") != std::string::npos);
    for (const char* c : {"render", "glsl", "compile", "check", "eval", "slice", "mesh", "merge", "bench", "watch", "preview"})
        CHECK(man.out.find(std::string(".SS \"sdfc ") + c + " ") != std::string::npos);
    CHECK(man.out.find(".TP\n\\fB\\-\\-width\\fR \\fIW\\fR\npicture width in pixels (default: 640).\n") != std::string::npos);
    CHECK(man.out.find("\\fB\\-D\\fR \\fINAME=VALUE\\fR") != std::string::npos);
    // Through groff, where it is installed: what `man sdfc` shows.
    if (std::system("command -v groff >/dev/null 2>&1") != 0) {
        WARN("SKIPPED: no groff, so the man page is not typeset");
        return;
    }
    const std::string page = test::write_temp("sdfc.1", man.out), txt = test::temp_dir() + "/sdfc.1.txt";
    REQUIRE(std::system(("groff -man -Tutf8 -P-c " + q(page) + " 2>" + q(txt + ".err") + " | col -b >" + q(txt)).c_str()) == 0);
    const std::string shown = test::slurp(txt);
    CHECK(test::slurp(txt + ".err") == "");
    CHECK(shown.find("sdfc - compile and render .sdf signed-distance-field scenes") != std::string::npos);
    CHECK(std::regex_search(shown, std::regex("--max-steps N\\s+sphere-tracing steps per ray \\(default: 256\\)")));
}

TEST_CASE("bash completes commands, options and their values from the table") {
    if (std::system("command -v bash >/dev/null 2>&1") != 0) {
        WARN("SKIPPED: no bash");
        return;
    }
    const auto script = run_sdfc("help --completion bash");
    REQUIRE(script.status == 0);
    CHECK(complete_bash(script.out, "sdfc ren") == "render");
    CHECK(complete_bash(script.out, "sdfc render x.sdf --wi") == "--width");
    CHECK(complete_bash(script.out, "sdfc render x.sdf --tonemap ") == "none reinhard aces");
    CHECK(complete_bash(script.out, "sdfc glsl x.sdf --target g") == "glsl330");
    CHECK(complete_bash(script.out, "sdfc mesh x.sdf --format ") == "stl obj ply 3mf");
    CHECK(complete_bash(script.out, "sdfc mesh x.sdf --resolution ") == "");  // a number: nothing to offer
    CHECK(complete_bash(script.out, "sdfc check x.sdf --max-rec") == "--max-recursion");
    CHECK(complete_bash(script.out, "sdfc watch --ru") == "--runs");
    CHECK(complete_bash(script.out, "sdfc watch --runs 2 ren") == "render");
    CHECK(complete_bash(script.out, "sdfc watch --runs 2 render x.sdf --ton") == "--tonemap");
    CHECK(complete_bash(script.out, "sdfc help --completion ") == "bash zsh");
}

TEST_CASE("the zsh completion is a valid #compdef script") {
    const auto script = run_sdfc("help --completion zsh");
    REQUIRE(script.status == 0);
    CHECK(script.out.rfind("#compdef sdfc\n", 0) == 0);
    CHECK(script.out.find("'--tonemap[tone mapping; none clips at 1]:none|reinhard|aces:(none reinhard aces)'") != std::string::npos);
    CHECK(script.out.find("'(--output -o)'{--output,-o}'[") != std::string::npos);
    if (std::system("command -v zsh >/dev/null 2>&1") != 0) {
        WARN("SKIPPED: no zsh, so the script is not parsed");
        return;
    }
    const std::string f = test::write_temp("_sdfc", script.out);
    CHECK(std::system(("zsh -n " + q(f)).c_str()) == 0);
}
