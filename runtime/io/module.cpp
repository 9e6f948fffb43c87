#include "runtime/io/module.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

namespace sdfc {

namespace fs = std::filesystem;

void* module_entry(const char* file, const char* env, const char* entry, std::string& failure) {
    std::vector<fs::path> candidates;
    if (const char* forced = std::getenv(env); forced && *forced) {
        candidates = {fs::path(forced)};
    } else {
        std::error_code ec;
        const fs::path dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
        if (ec || dir.empty()) {
            candidates = {fs::path(file)};  // the loader's own search
        } else {
            candidates = {dir / file, dir.parent_path() / "lib" / "sdfc" / file};
            // (a test or bench tool in build/tests, build/bench: the build folder's; not beside
            // a binary copied anywhere else, where a folder up may hold another build's module)
            if (fs::exists(dir.parent_path() / "CMakeCache.txt", ec)) candidates.insert(candidates.begin() + 1, dir.parent_path() / file);
        }
    }
    std::string tried;
    for (const fs::path& p : candidates) {
        std::error_code ec;
        if (p.has_parent_path() && !fs::exists(p, ec)) {
            tried += (tried.empty() ? "" : ", ") + p.string();
            continue;
        }
        void* h = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!h) {
            const char* why = dlerror();
            failure = why ? why : p.string() + ": cannot be opened";
            return nullptr;
        }
        void* sym = dlsym(h, entry);
        if (!sym) failure = p.string() + " is not this build's " + file;
        return sym;
    }
    failure = "not found (looked for " + tried + ")";
    return nullptr;
}

}  // namespace sdfc
