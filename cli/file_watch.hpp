// Waiting for a save: what `sdfc watch` and `sdfc preview` watch between runs (inotify on
// the files' folders, so editors that save by renaming a new file over the old are seen).
#pragma once
#include <sys/types.h>

#include <map>
#include <string>
#include <vector>

namespace sdfc::cli {

// A file's identity and age: a save changes one of them (a rename, a write).
struct Stamp {
    bool exists = false;
    ino_t ino = 0;
    long long mtime_ns = 0, size = 0;
    bool operator==(const Stamp& o) const { return exists == o.exists && ino == o.ino && mtime_ns == o.mtime_ns && size == o.size; }
};

Stamp stamp_of(const std::string& path);

// The files a run read (the scene, its imports: take_loaded_paths), stamped now; when it
// read none (its scene did not open), the .sdf and .vm arguments of `command`.
std::map<std::string, Stamp> files_read(const std::vector<std::string>& command);
// ... from the paths already taken.
std::map<std::string, Stamp> files_read(const std::vector<std::string>& command, const std::vector<std::string>& loaded);

// Waits until one of `files` is saved and then `debounce_ms` pass without another event.
void wait_for_change(const std::map<std::string, Stamp>& files, int debounce_ms);

}  // namespace sdfc::cli
