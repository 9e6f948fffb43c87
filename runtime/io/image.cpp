// write_image, check_image_output and read_image, forwarded to the image module
// (libsdfc_image.so, runtime/io/oiio): opened on first use, so the commands that write no
// image start without OpenImageIO and its libraries.
#include "runtime/io/image.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "runtime/io/atomic_file.hpp"
#include "runtime/io/image_backend.hpp"

namespace sdfc {
namespace {

namespace fs = std::filesystem;

constexpr const char* kModule = "libsdfc_image.so";

// What the module takes from the program: referenced here, so every program that writes
// images links them in (a static library's object files come only when referenced).
[[maybe_unused]] __attribute__((used)) void (*const kForTheModule[])() = {
    reinterpret_cast<void (*)()>(&write_file),     reinterpret_cast<void (*)()>(&temp_path_for),
    reinterpret_cast<void (*)()>(&write_error),    reinterpret_cast<void (*)()>(&resolve_output),
    reinterpret_cast<void (*)()>(&linear_to_srgb), reinterpret_cast<void (*)()>(&srgb_to_linear),
    reinterpret_cast<void (*)()>(&heat_color),     reinterpret_cast<void (*)()>(&aov_side_path),
};

// Next to the executable (the build folder; a test in build/tests finds it one up), or in
// ../lib/sdfc beside an installed bin/; SDFC_IMAGE_MODULE names another.
std::vector<fs::path> module_candidates() {
    if (const char* forced = std::getenv("SDFC_IMAGE_MODULE"); forced && *forced) return {fs::path(forced)};
    std::error_code ec;
    const fs::path dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
    if (ec || dir.empty()) return {fs::path(kModule)};  // the loader's own search
    return {dir / kModule, dir.parent_path() / kModule, dir.parent_path() / "lib" / "sdfc" / kModule};
}

#ifdef SDFC_IMAGE_BUILTIN
// Linked in (sanitizer and fuzz builds: CMakeLists.txt says why).
const ImageBackend& backend() { return *sdfc_image_backend(); }
#else
const ImageBackend& backend() {
    static const ImageBackend* loaded = nullptr;
    static std::string failure;
    static std::once_flag once;
    std::call_once(once, [] {
        std::string tried;
        for (const fs::path& p : module_candidates()) {
            std::error_code ec;
            if (p.has_parent_path() && !fs::exists(p, ec)) {
                tried += (tried.empty() ? "" : ", ") + p.string();
                continue;
            }
            void* h = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (!h) {
                failure = dlerror();
                return;
            }
            auto entry = reinterpret_cast<const ImageBackend* (*)()>(dlsym(h, "sdfc_image_backend"));
            const ImageBackend* b = entry ? entry() : nullptr;
            if (!b || b->version != kImageBackendVersion) {
                failure = p.string() + " is not this build's image module";
                return;
            }
            loaded = b;
            return;
        }
        failure = "not found (looked for " + tried + ")";
    });
    if (!loaded) throw std::runtime_error("cannot load the image library " + std::string(kModule) + ": " + failure);
    return *loaded;
}
#endif

}  // namespace

void write_image(const std::string& path, const Image& img, const WriteOptions& opt) { backend().write_image(path, img, opt); }

void check_image_output(const std::string& path, const std::string& format) { backend().check_image_output(path, format); }

Image read_image(const std::string& path) { return backend().read_image(path); }

}  // namespace sdfc
