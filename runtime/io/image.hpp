// Images: linear-light float pixels plus optional AOV planes, and their files.
//
// Files go through OpenImageIO; the format follows the extension. png/jpg/jpeg/tif/tiff/
// bmp/tga/... are written as 8-bit sRGB; exr and hdr as linear float. A fourth channel is
// alpha (A): premultiplied colour in float files, straight in 8-bit ones. EXR carries the
// AOVs as extra channels (`Z`, `N.x N.y N.z`, `steps.Y`); every other format gets side
// files next to the image: `STEM.depth.png`, `STEM.normal.png`, `STEM.steps.png`
// (visualised), or beside a float hdr/pfm `STEM.NAME.exr` with the plane's own values.
// Every file is encoded, decoded again as a check, and written by write_file
// (runtime/io/atomic_file.hpp): a full disk, a crash or a kill never leaves a partial file,
// an existing output is only replaced by a complete one, devices and FIFOs are written through.
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace sdfc {

// An extra per-pixel plane: "depth" (1 channel, ray distance of the first hit, +inf for
// misses), "normal" (3, world-space unit normal of the first hit, 0 for misses), "steps"
// (1, sphere-tracing steps of the primary ray).
struct AovPlane {
    std::string name;
    int channels = 1;
    std::vector<float> data;  // width * height * channels, row-major, row 0 at the top
};

struct Image {
    int width = 0, height = 0, channels = 3;
    // A band of a taller picture (sdfc render --tiles): its first row there, and that
    // picture's height; 0 and 0 for a whole picture. Written as an EXR data window.
    int row0 = 0, full_height = 0;
    // A band's picture (a hash of what was rendered; EXR attribute sdfc:picture): sdfc merge
    // joins only bands of one picture. Empty: unknown.
    std::string picture;
    std::vector<float> pixels;  // linear RGB (channels interleaved), row-major, row 0 at the top
    std::vector<AovPlane> aovs;

    Image() = default;
    Image(int w, int h, int c = 3) : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c, 0.0f) {}

    float& at(int x, int y, int c) { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
    float at(int x, int y, int c) const { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
    const AovPlane* aov(std::string_view name) const {
        for (const auto& a : aovs)
            if (a.name == name) return &a;
        return nullptr;
    }
};

struct WriteOptions {
    bool aov_side_files = true;  // non-EXR formats: write STEM.NAME.png for each AOV plane
    std::string format;          // for the path "-" (standard output): the format's extension, "png"
};

// Throws std::runtime_error (with the path and the reason) on failure; the target is then
// left as it was and no temporary file remains.
void write_image(const std::string& path, const Image& img, const WriteOptions& opt = {});

// The checks write_image makes before it encodes anything, for callers to make before the
// work: the path can be written (resolve_output) and its extension names an image format
// OpenImageIO writes (for "-", standard output, `format` names it). Throws
// std::runtime_error "cannot write 'PATH': REASON".
void check_image_output(const std::string& path, const std::string& format = "");

// Reads any format OpenImageIO knows. 8-bit (and other integer) files are decoded from sRGB
// to linear; float files are taken as linear. Channels named Z / N.x N.y N.z / steps become
// the AOV planes depth / normal / steps; the rest are the colour channels.
Image read_image(const std::string& path);

// The side-file name of an AOV plane: "dir/out.png" + "depth" -> "dir/out.depth.png".
std::string aov_side_path(const std::string& path, const std::string& aov);

float linear_to_srgb(float v);
float srgb_to_linear(float v);

// A heat-map colour for t in [0, 1] (dark blue -> magenta -> orange -> pale yellow), as
// display (sRGB-encoded) values in [0, 1]. Used by the steps view and the steps side file.
void heat_color(float t, float rgb[3]);

}  // namespace sdfc
