// `sdfc watch [--runs N] [--debounce MS] CMD ARGS...`: runs a command, then again after every
// save of its scene or of a file the scene imports (inotify on their folders: editors that
// save by renaming are seen too), once the saves have been quiet for the debounce time. A
// failed run prints its diagnostics and writes nothing (outputs are atomic), so the last
// good output stays. One line per run on standard error. Ctrl-C ends it (temporary files
// removed by install_temp_cleanup's handlers).
#include <poll.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/common.hpp"
#include "cli/output_checks.hpp"
#include "compiler/base/source.hpp"

namespace sdfc::cli {
namespace {

namespace fs = std::filesystem;

const std::set<std::string> kWatchable{"render", "glsl", "check", "slice", "mesh", "eval", "compile"};

// A file's identity and age: a save changes one of them (a rename, a write).
struct Stamp {
    bool exists = false;
    ino_t ino = 0;
    long long mtime_ns = 0, size = 0;
    bool operator==(const Stamp& o) const { return exists == o.exists && ino == o.ino && mtime_ns == o.mtime_ns && size == o.size; }
};

Stamp stamp_of(const std::string& path) {
    struct stat st {};
    Stamp s;
    if (::stat(path.c_str(), &st) != 0) return s;
    s.exists = true, s.ino = st.st_ino, s.size = st.st_size;
    s.mtime_ns = (long long)st.st_mtim.tv_sec * 1000000000LL + st.st_mtim.tv_nsec;
    return s;
}

// Waits until one of `files` is saved and then `debounce_ms` pass without another event.
void wait_for_change(const std::map<std::string, Stamp>& files, int debounce_ms) {
    const int fd = inotify_init1(IN_CLOEXEC);
    if (fd < 0) throw std::runtime_error(fmt::format("watch: cannot use inotify: {}", std::strerror(errno)));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    std::map<int, std::pair<std::string, std::set<std::string>>> dirs;  // watch -> folder, names in it
    for (const auto& [path, stamp] : files) {
        const fs::path p(path);
        const std::string dir = p.parent_path().empty() ? "." : p.parent_path().string();
        const int wd = inotify_add_watch(fd, dir.c_str(), IN_CLOSE_WRITE | IN_MOVED_TO | IN_CREATE | IN_DELETE | IN_ATTRIB | IN_MODIFY);
        if (wd < 0) throw std::runtime_error(fmt::format("watch: cannot watch '{}': {}", dir, std::strerror(errno)));
        dirs[wd].first = dir;
        dirs[wd].second.insert(p.filename().string());
    }
    // A save between the last run and the watches: seen by the stamps.
    bool changed = false;
    for (const auto& [path, stamp] : files) changed |= !(stamp_of(path) == stamp);
    alignas(inotify_event) char buf[1 << 14];
    for (;;) {
        pollfd p{fd, POLLIN, 0};
        const int r = ::poll(&p, 1, changed ? debounce_ms : -1);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) throw std::runtime_error(fmt::format("watch: {}", std::strerror(errno)));
        if (r == 0) return;  // quiet for the debounce time after a change
        const ssize_t n = ::read(fd, buf, sizeof buf);
        for (ssize_t off = 0; n > 0 && off < n;) {
            const auto* e = reinterpret_cast<const inotify_event*>(buf + off);
            auto it = dirs.find(e->wd);
            if (it != dirs.end() && e->len > 0 && it->second.second.count(e->name)) changed = true;
            off += ssize_t(sizeof(inotify_event) + e->len);
        }
    }
}

}  // namespace

int cmd_watch(const std::vector<std::string>& args, int (*run)(const std::vector<std::string>&)) {
    long runs = -1;  // until Ctrl-C
    int debounce_ms = 100;
    size_t i = 0;
    for (; i < args.size() && args[i].rfind("--", 0) == 0; ++i) {
        const std::string& a = args[i];
        if (a == "--help") {
            write_stdout("usage: sdfc watch [--runs N] [--debounce MS] CMD ARGS...\n"
                         "  runs `sdfc CMD ARGS...` now and after every save of its scene or of a file it imports;\n"
                         "  CMD is render, glsl, check, slice, mesh, eval or compile; --runs N stops after N runs,\n"
                         "  --debounce MS (default 100) waits that long after the last save\n");
            return 0;
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
        std::map<std::string, Stamp> files;
        for (const std::string& p : take_loaded_paths()) files[p] = stamp_of(p);
        if (files.empty())
            for (size_t k = 1; k < command.size(); ++k)
                if (fs::path(command[k]).extension() == ".sdf" || fs::path(command[k]).extension() == ".vm") files[command[k]] = stamp_of(command[k]);
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
