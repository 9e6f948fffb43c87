// What is made from the option table (options.hpp): the help pages, the man page and the
// bash and zsh completion scripts.
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "cli/options.hpp"

namespace sdfc::cli {
namespace {

const char* kAbout = "compile and render .sdf signed-distance-field scenes";

const char* kScenes =
    "SCENE is a .sdf script or a .vm model (Prospero/Fidget flat SSA format); - reads a script from standard input (its "
    "imports relative to the working folder). -o - writes to standard output.";
const char* kConventions =
    "`sdfc CMD --help` lists a command's options and their defaults; -- ends the options. Exit status: 0 done, 1 an error "
    "in the script or while working (path:line:col: error: ...), 2 a bad command line (sdfc: error: ...).";

// `text` in lines of at most `width` columns, each after `indent` spaces; the first line's
// indent is already written by the caller when `hang` is set.
std::string wrap(const std::string& text, size_t indent, size_t width, bool hang = false) {
    std::istringstream words(text);
    std::string out, line, w;
    auto flush = [&] {
        if (line.empty()) return;
        out += (hang && out.empty() ? "" : std::string(indent, ' ')) + line + "\n";
        line.clear();
    };
    while (words >> w) {
        if (!line.empty() && indent + line.size() + 1 + w.size() > width) flush();
        line += (line.empty() ? "" : " ") + w;
    }
    flush();
    return out;
}

std::string spec_of(const Option& o) {
    std::string s = o.alt.empty() ? o.name : o.alt + ", " + o.name;
    if (!o.value.empty()) s += " " + o.value;
    return s;
}

// The default is kept on one line: its spaces are \x01 until wrap() has run (unglue()).
std::string help_of(const Option& o) {
    if (o.def.empty()) return o.help;
    std::string d = "(default: " + o.def + ")";
    for (char& ch : d)
        if (ch == ' ') ch = '\x01';
    return o.help + " " + d;
}

std::string unglue(std::string s) {
    for (char& ch : s)
        if (ch == '\x01') ch = ' ';
    return s;
}

std::string option_lines(const std::vector<Option>& opts) {
    constexpr size_t kCol = 30, kWidth = 100;
    std::string out;
    for (const Option& o : opts) {
        std::string spec = "  " + spec_of(o);
        if (spec.size() + 2 > kCol) out += spec + "\n" + unglue(wrap(help_of(o), kCol, kWidth));
        else out += spec + std::string(kCol - spec.size(), ' ') + unglue(wrap(help_of(o), kCol, kWidth, true));
    }
    return out;
}

// ---- roff (man(7)) ----
std::string roff(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '\\') o += "\\e";
        else if (c == '-') o += "\\-";
        else o += c;
    }
    if (!o.empty() && (o[0] == '.' || o[0] == '\'')) o = "\\&" + o;
    return o;
}

std::string man_options(const std::vector<Option>& opts) {
    std::string out;
    for (const Option& o : opts) {
        std::string head = "\\fB" + roff(o.alt.empty() ? o.name : o.alt + ", " + o.name) + "\\fR";
        if (!o.value.empty()) head += " \\fI" + roff(o.value) + "\\fR";
        out += ".TP\n" + head + "\n" + roff(unglue(help_of(o))) + ".\n";
    }
    return out;
}

// ---- shells ----
std::string words_of(const std::vector<Option>& opts) {
    std::string w;
    for (const Option& o : opts) {
        w += (w.empty() ? "" : " ") + o.name;
        if (!o.alt.empty()) w += " " + o.alt;
    }
    return w;
}

std::vector<Option> all_options(const CommandSpec& c) {
    std::vector<Option> v = c.options;
    if (c.scene_options) v.insert(v.end(), scene_options().begin(), scene_options().end());
    v.push_back({"--help", "-h", "", "", "", "this command's options"});
    return v;
}

std::string bash_script() {
    std::string names;
    for (const CommandSpec& c : commands()) names += (names.empty() ? "" : " ") + c.name;
    std::string s = "# bash completion for sdfc, made by `sdfc help --completion bash` from its option table.\n"
                    "_sdfc() {\n"
                    "    local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} i=1 cmd\n"
                    "    COMPREPLY=()\n"
                    "    # `sdfc watch [OPTIONS] CMD ...` completes CMD's words after watch's own.\n"
                    "    while :; do\n"
                    "        cmd=${COMP_WORDS[i]}\n"
                    "        if (( COMP_CWORD == i )); then\n"
                    "            COMPREPLY=($(compgen -W \"" + names + " --help --version\" -- \"$cur\"))\n"
                    "            return\n"
                    "        fi\n"
                    "        [[ $cmd == watch ]] || break\n"
                    "        ((i++))\n"
                    "        while [[ ${COMP_WORDS[i]} == --runs || ${COMP_WORDS[i]} == --debounce ]] && (( i + 1 < COMP_CWORD )); do ((i += 2)); done\n"
                    "        if (( COMP_CWORD > i )) && [[ ${COMP_WORDS[i]} != -* ]]; then continue; fi\n"
                    "        cmd=watch\n"
                    "        break\n"
                    "    done\n"
                    "    case $cmd in\n";
    for (const CommandSpec& c : commands()) {
        const std::vector<Option> opts = all_options(c);
        s += "    " + c.name + ")\n        case $prev in\n";
        for (const Option& o : opts) {
            if (o.value.empty()) continue;
            const std::string pat = o.alt.empty() ? o.name : o.name + "|" + o.alt;
            if (o.choices == "FILE") s += "        " + pat + ") COMPREPLY=($(compgen -f -- \"$cur\")); return ;;\n";
            else if (!o.choices.empty() && o.name != "--aov")
                s += "        " + pat + ") COMPREPLY=($(compgen -W \"" + o.choices + "\" -- \"$cur\")); return ;;\n";
            else s += "        " + pat + ") return ;;\n";  // a number or a list: nothing to offer
        }
        s += "        esac\n"
             "        if [[ $cur == -* ]]; then\n"
             "            COMPREPLY=($(compgen -W \"" + words_of(opts) + "\" -- \"$cur\"))\n";
        if (c.name == "watch") {
            s += "        else\n"
                 "            COMPREPLY=($(compgen -W \"render glsl check slice mesh eval compile\" -- \"$cur\"))\n";
        } else if (c.name == "help") {
            s += "        else\n"
                 "            COMPREPLY=($(compgen -W \"" + names + "\" -- \"$cur\"))\n";
        } else {
            s += "        else\n"
                 "            COMPREPLY=($(compgen -f -X '!*.@(sdf|vm)' -- \"$cur\") $(compgen -d -- \"$cur\"))\n";
        }
        s += "        fi\n        ;;\n";
    }
    s += "    esac\n}\ncomplete -o filenames -o bashdefault -F _sdfc sdfc\n";
    return s;
}

std::string zsh_text(const std::string& s) {  // inside '...[...]' of _arguments
    std::string o;
    for (char c : s) {
        if (c == '\'') o += "'\\''";
        else if (c == '[' || c == ']' || c == ':' || c == '\\') o += std::string("\\") + c;
        else o += c;
    }
    return o;
}

std::string zsh_script() {
    std::string s = "#compdef sdfc\n# zsh completion for sdfc, made by `sdfc help --completion zsh` from its option table.\n"
                    "_sdfc() {\n    local -a commands\n    commands=(\n";
    for (const CommandSpec& c : commands()) s += "        '" + c.name + ":" + zsh_text(c.summary) + "'\n";
    s += "    )\n"
         "    if (( CURRENT == 2 )); then\n        _describe -t commands 'sdfc command' commands\n        return\n    fi\n"
         "    local cmd=$words[2]\n    shift words\n    (( CURRENT-- ))\n    case $cmd in\n";
    for (const CommandSpec& c : commands()) {
        s += "    " + c.name + ")\n        _arguments -s";
        for (const Option& o : all_options(c)) {
            std::string action;
            if (o.value.empty()) action = "";
            else if (o.choices == "FILE") action = ":" + zsh_text(o.value) + ":_files";
            else if (!o.choices.empty() && o.name != "--aov") action = ":" + zsh_text(o.value) + ":(" + o.choices + ")";
            else action = ":" + zsh_text(o.value) + ": ";
            const std::string repeat = o.name == "-D" ? "*" : "";
            const std::string desc = "[" + zsh_text(o.help) + "]";
            if (!o.alt.empty()) {
                s += " \\\n            '(" + o.name + " " + o.alt + ")'{" + o.name + "," + o.alt + "}'" + desc + action + "'";
            } else {
                s += " \\\n            '" + repeat + o.name + desc + action + "'";
            }
        }
        if (c.name == "watch") s += " \\\n            '1:command:(render glsl check slice mesh eval compile)' '*::arguments:_files'";
        else if (c.name == "help") s += " \\\n            '1:command:(" + [] {
                std::string n;
                for (const CommandSpec& k : commands()) n += (n.empty() ? "" : " ") + k.name;
                return n;
            }() + ")'";
        else s += " \\\n            '*:scene:_files -g \"*.(sdf|vm)\"'";
        s += "\n        ;;\n";
    }
    s += "    esac\n}\n_sdfc \"$@\"\n";
    return s;
}

}  // namespace

std::string global_help() {
    std::string s = fmt::format("sdfc — {}\n\nusage:\n", kAbout);
    for (const CommandSpec& c : commands()) s += "  sdfc " + c.name + " " + c.args + "\n" + wrap(c.summary, 6, 100);
    s += "  sdfc --help | --version | CMD --help\n\n";
    s += wrap(kScenes, 0, 100);
    s += wrap("Every command that reads a scene takes -D NAME=VALUE (the script's top-level `let NAME` takes VALUE, as "
              "OpenSCAD's -D) and the safety limits --max-recursion, --max-iterations, --max-calls, --max-shapes, "
              "--max-shape-depth, --max-list, --max-ops, --max-file-size, --max-nesting, --max-pixels, --max-frames.",
              0, 100);
    s += wrap(kConventions, 0, 100);
    return s;
}

std::string command_help(const CommandSpec& c) {
    const bool listed = c.args.find("[-") != std::string::npos;  // the synopsis names the options already
    std::string s = "usage: sdfc " + c.name + " " + c.args + (listed || (c.options.empty() && !c.scene_options) ? "" : " [options]") + "\n";
    s += wrap(c.summary, 0, 100);
    if (!c.options.empty()) s += "\noptions:\n" + option_lines(c.options);
    if (c.scene_options) s += "\nscene options (-D, and the safety limits: docs/language.md):\n" + option_lines(scene_options());
    s += "\n";
    if (!c.notes.empty()) s += wrap(c.notes, 0, 100) + "\n";
    if (c.scene_options) s += wrap(kScenes, 0, 100);
    return s;
}

std::string man_page(const std::string& version) {
    std::string s = ".\\\" The man page of sdfc, made by `sdfc help --man` from its option table.\n";
    s += ".TH SDFC 1 \"\" \"sdfc " + roff(version) + "\" \"User Commands\"\n";
    s += ".SH NAME\nsdfc \\- " + roff(kAbout) + "\n";
    s += ".SH SYNOPSIS\n";
    for (const CommandSpec& c : commands()) s += ".B sdfc " + roff(c.name) + "\n" + roff(c.args) + "\n.br\n";
    s += ".SH DESCRIPTION\n" + roff(kScenes) + "\n.PP\n" + roff(kConventions) + "\n";
    s += ".SH COMMANDS\n";
    for (const CommandSpec& c : commands()) {
        s += ".SS \"sdfc " + roff(c.name) + " " + roff(c.args) + "\"\n" + roff(c.summary) + ".\n";
        if (!c.notes.empty()) s += ".PP\n" + roff(c.notes) + "\n";
        s += man_options(c.options);
        if (c.scene_options) s += ".TP\n\\fIscene options\\fR\nsee SCENE OPTIONS.\n";
    }
    s += ".SH \"SCENE OPTIONS\"\nEvery command that reads a scene takes these (the limits: docs/language.md).\n";
    s += man_options(scene_options());
    s += ".SH \"EXIT STATUS\"\n0: done. 1: an error in the script or while working. 2: a bad command line.\n";
    s += ".SH ENVIRONMENT\n.TP\n.B SDFC_IMAGE_MODULE\nthe image library to load (libsdfc_image.so) instead of the one beside sdfc.\n";
    s += ".TP\n.B SDFC_PREVIEW_MODULE\nthe preview's server library to load (libsdfc_preview.so) instead of the one beside sdfc.\n";
    s += ".SH \"SEE ALSO\"\nThe language: docs/language.md; the shapes and operations: docs/reference.md.\n";
    return s;
}

std::string completion_script(const std::string& shell) {
    if (shell == "bash") return bash_script();
    if (shell == "zsh") return zsh_script();
    return "";
}

}  // namespace sdfc::cli
