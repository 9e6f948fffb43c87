// write_image, check_image_output and read_image, forwarded to the image module
// (libsdfc_image.so, runtime/io/oiio): opened on first use, so the commands that write no
// image start without OpenImageIO and its libraries.
#include "runtime/io/image.hpp"

#include <mutex>
#include <stdexcept>
#include <string>

#include "runtime/io/atomic_file.hpp"
#include "runtime/io/image_backend.hpp"
#include "runtime/io/module.hpp"

namespace sdfc {
namespace {

constexpr const char* kModule = "libsdfc_image.so";

// What the module takes from the program: referenced here, so every program that writes
// images links them in (a static library's object files come only when referenced).
[[maybe_unused]] __attribute__((used)) void (*const kForTheModule[])() = {
    reinterpret_cast<void (*)()>(&write_file),     reinterpret_cast<void (*)()>(&temp_path_for),
    reinterpret_cast<void (*)()>(&write_error),    reinterpret_cast<void (*)()>(&resolve_output),
    reinterpret_cast<void (*)()>(&linear_to_srgb), reinterpret_cast<void (*)()>(&srgb_to_linear),
    reinterpret_cast<void (*)()>(&heat_color),     reinterpret_cast<void (*)()>(&aov_side_path),
};

#ifdef SDFC_IMAGE_BUILTIN
// Linked in (sanitizer and fuzz builds: CMakeLists.txt says why).
const ImageBackend& backend() { return *sdfc_image_backend(); }
#else
const ImageBackend& backend() {
    static const ImageBackend* loaded = nullptr;
    static std::string failure;
    static std::once_flag once;
    std::call_once(once, [] {
        auto entry = reinterpret_cast<const ImageBackend* (*)()>(module_entry(kModule, "SDFC_IMAGE_MODULE", "sdfc_image_backend", failure));
        if (!entry) return;
        const ImageBackend* b = entry();
        if (!b || b->version != kImageBackendVersion) {
            failure = "it is not this build's image module";
            return;
        }
        loaded = b;
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
