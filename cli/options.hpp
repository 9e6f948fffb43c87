// The one table of sdfc's commands and their options (options.cpp): `sdfc --help`, every
// `sdfc CMD --help`, the man page and the bash and zsh completions are all made from it
// (help.cpp), and the commands read only options it lists (Args::declare checks), so the
// documentation cannot drift from what the command line takes.
#pragma once
#include <string>
#include <vector>

namespace sdfc::cli {

struct Option {
    std::string name;     // "--width"
    std::string alt;      // another spelling ("-o" for "--output"), or ""
    std::string value;    // what it takes ("W", "X,Y,Z"), or "" for a flag
    std::string choices;  // the values it takes, space-separated, for completion; "FILE": a path
    std::string def;      // its default, or "" (none, or said in the help)
    std::string help;     // one sentence or two, no final stop
};

struct CommandSpec {
    std::string name;     // "render"
    std::string args;     // what follows the name ("SCENE... -o OUT")
    std::string summary;  // one line
    std::vector<Option> options;
    std::string notes;    // paragraphs after the options, or ""
    bool scene_options;   // also takes -D and the safety limits (scene_options())
};

// Every command, in the order `sdfc --help` lists them.
const std::vector<CommandSpec>& commands();
// The command called `name`, or nullptr.
const CommandSpec* find_command(const std::string& name);
// -D and the safety limits: every command that reads a scene takes them.
const std::vector<Option>& scene_options();
// Every option name `cmd` takes (both spellings), for Args::declare.
std::vector<std::string> option_names(const CommandSpec& cmd);

// Made from the table (help.cpp).
std::string global_help();                             // sdfc --help
std::string command_help(const CommandSpec& cmd);      // sdfc CMD --help
std::string man_page(const std::string& version);      // sdfc help --man: roff, for man(1)
std::string completion_script(const std::string& shell);  // sdfc help --completion bash|zsh; "" if unknown

}  // namespace sdfc::cli
