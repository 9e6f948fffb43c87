// `sdfc watch [--runs N] [--debounce MS] CMD ARGS...`: runs a command, then again after every
// save of its scene or of a file the scene imports (inotify on their folders: editors that
// save by renaming are seen too), once the saves have been quiet for the debounce time. A
// failed run prints its diagnostics and writes nothing (outputs are atomic), so the last
// good output stays. One line per run on standard error. Ctrl-C ends it (temporary files
// removed by install_temp_cleanup's handlers).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/common.hpp"
#include "cli/file_watch.hpp"
#include "cli/options.hpp"
#include "cli/output_checks.hpp"
#include "compiler/base/source.hpp"

namespace sdfc::cli {
namespace {

const std::set<std::string> kWatchable{"render", "glsl", "check", "slice", "mesh", "eval", "compile"};

}  // namespace

int cmd_watch(const std::vector<std::string>& args, int (*run)(const std::vector<std::string>&)) {
    long runs = -1;  // until Ctrl-C
    int debounce_ms = 100;
    size_t i = 0;
    for (; i < args.size() && (args[i].rfind("--", 0) == 0 || args[i] == "-h"); ++i) {
        const std::string& a = args[i];
        if (a == "--help" || a == "-h") {
            write_stdout(command_help(*find_command("watch")));
            return 0;
        }
        if (a == "--") {  // (ends watch's options, as for every command)
            ++i;
            break;
        }
        if (a != "--runs" && a != "--debounce") throw UsageError(fmt::format("unknown watch option '{}' (--runs N, --debounce MS, then the command)", a));
        if (i + 1 >= args.size()) throw UsageError(fmt::format("{} needs a value", a));
        if (a == "--runs") runs = Args::to_int("--runs", args[++i], 1, 1000000000);
        else debounce_ms = Args::to_int("--debounce", args[++i], 0, 60000);
    }
    if (i >= args.size()) throw UsageError("watch needs a command: sdfc watch render SCENE -o OUT (or glsl, check, slice, mesh, eval, compile)");
    const std::vector<std::string> command(args.begin() + std::ptrdiff_t(i), args.end());
    if (!kWatchable.count(command[0]))
        throw UsageError(fmt::format("watch runs render, glsl, check, slice, mesh, eval or compile, not '{}'", command[0]));
    if (std::find(command.begin() + 1, command.end(), "-") != command.end())
        throw UsageError("watch needs a scene file: standard input (-) is read once");
    int rc = 0;
    for (long n = 1; runs < 0 || n <= runs; ++n) {
        (void)take_loaded_paths();
        forget_warnings();
        const auto t0 = std::chrono::steady_clock::now();
        rc = run(command);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        // What the run read (the scene, its imports); a scene that failed to open too.
        const std::vector<std::string> loaded = take_loaded_paths();
        // A command line refused before any scene was read (a missing -o, an unknown
        // option): no save can fix it.
        if (rc == 2 && n == 1 && loaded.empty()) throw UsageError("watch stops: the command line above is wrong, and no save of the scene can fix it");
        const std::map<std::string, Stamp> files = files_read(command, loaded);
        std::fprintf(stderr, "sdfc watch: run %ld %s in %.1f ms; watching %zu file%s\n", n, rc == 0 ? "ok" : "failed", ms, files.size(),
                     files.size() == 1 ? "" : "s");
        std::fflush(stdout);
        if (runs >= 0 && n == runs) break;
        if (files.empty()) throw UsageError("watch found no scene file to watch");
        wait_for_change(files, debounce_ms);
    }
    return rc;
}

}  // namespace sdfc::cli
