#include "cli/file_watch.hpp"

#include <poll.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "compiler/base/source.hpp"

namespace sdfc::cli {

namespace fs = std::filesystem;

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


std::map<std::string, Stamp> files_read(const std::vector<std::string>& command) { return files_read(command, take_loaded_paths()); }

std::map<std::string, Stamp> files_read(const std::vector<std::string>& command, const std::vector<std::string>& loaded) {
    std::map<std::string, Stamp> files;
    for (const std::string& p : loaded) files[p] = stamp_of(p);
    if (files.empty())
        for (size_t k = 1; k < command.size(); ++k)
            if (fs::path(command[k]).extension() == ".sdf" || fs::path(command[k]).extension() == ".vm") files[command[k]] = stamp_of(command[k]);
    return files;
}

}  // namespace sdfc::cli
