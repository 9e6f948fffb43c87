// The table the image module (runtime/io/oiio, libsdfc_image.so) hands to the loader in
// runtime/io/image.cpp. Both sides are built together, with the same compiler and library:
// C++ types and exceptions cross; the version catches a module left from another build.
#pragma once
#include <string>

#include "runtime/io/image.hpp"

namespace sdfc {

// Bumped by hand when the table changes; the sizes of the types that cross catch most layout
// changes nobody bumped it for (a module from before Image::picture crashed in write_image).
inline constexpr int kImageBackendVersion =
    3 + 16 * int(sizeof(Image) + 1024 * sizeof(WriteOptions) + 65536 * sizeof(AovPlane)) % 1000003;

struct ImageBackend {
    int version;
    void (*write_image)(const std::string& path, const Image& img, const WriteOptions& opt);
    void (*check_image_output)(const std::string& path, const std::string& format);
    Image (*read_image)(const std::string& path);
};

}  // namespace sdfc

// The module's one exported symbol.
extern "C" const sdfc::ImageBackend* sdfc_image_backend();
