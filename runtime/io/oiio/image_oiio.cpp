// The image files, through OpenImageIO: a module of its own (libsdfc_image.so), opened by
// runtime/io/image.cpp at the first image read or write, so that the commands that write
// none do not load the ~250 libraries Debian's OpenImageIO links.
#include "runtime/io/image.hpp"
#include "runtime/io/image_backend.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "compiler/render/rules.h"
#include "runtime/io/atomic_file.hpp"

namespace sdfc {

namespace fs = std::filesystem;

namespace {

std::string lower_ext(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}

bool is_float_format(const std::string& ext) { return ext == ".exr" || ext == ".hdr" || ext == ".pfm"; }

uint8_t to_u8(float display) {
    if (!(display > 0.0f)) return 0;
    if (display >= 1.0f) return 255;
    return static_cast<uint8_t>(display * 255.0f + 0.5f);
}

float finite_or_zero(float v) { return std::isfinite(v) ? v : 0.0f; }

// Formats that are no image file: OpenImageIO's "null" writes nothing, "term" draws on a terminal.
bool is_file_format(const char* name) { return std::strcmp(name, "null") != 0 && std::strcmp(name, "term") != 0; }

std::unique_ptr<OIIO::ImageOutput> image_output_for(const std::string& path, OIIO::Filesystem::IOProxy* proxy = nullptr) {
    const std::string ext = fs::path(path).extension().string();
    if (ext.empty() || ext == ".")
        throw std::runtime_error(write_error(path, "no extension to choose the image format from (.png, .jpg, .exr, .hdr, .tif, ...)"));
    auto out = OIIO::ImageOutput::create(path, proxy);
    (void)OIIO::geterror();  // clear: the message names nothing useful
    if (!out || !is_file_format(out->format_name()))
        throw std::runtime_error(write_error(path, "unknown image format '" + ext + "' (known: .png, .jpg, .exr, .hdr, .tif, .bmp, .tga, ...)"));
    return out;
}

// A full decode of what was encoded: a truncated, empty or broken encoding is found here,
// not in a file later. decodes_in_memory: false also where no reader takes the bytes from
// memory; verify_file throws "cannot write 'PATH': ..." (`file` named as PATH).
bool decodes(OIIO::ImageInput* in, int width, int height, int nch, std::string* err) {
    if (!in) return false;
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> px(size_t(std::max(spec.width, 0)) * std::max(spec.height, 0) * std::max(spec.nchannels, 1));
    bool ok = spec.width == width && spec.height == height && spec.nchannels >= std::min(nch, 3) &&
              in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data());
    if (!ok && err) *err = in->geterror();
    in->close();
    return ok;
}

bool decodes_in_memory(const std::string& path, const std::vector<unsigned char>& mem, int width, int height, int nch) {
    OIIO::Filesystem::IOMemReader reader(mem.data(), mem.size());
    // OpenImageIO opens a file of the name it is given even with a proxy (a FIFO there
    // would block): a name that cannot exist, with the extension that picks the reader.
    const std::string none = "/dev/null/encoded" + fs::path(path).extension().string();
    auto probe = OIIO::ImageInput::create(none, false, nullptr, &reader);
    bool ok = probe && probe->supports("ioproxy");
    probe.reset();
    if (ok) {
        auto in = OIIO::ImageInput::open(none, nullptr, &reader);
        ok = decodes(in.get(), width, height, nch, nullptr);
    }
    (void)OIIO::geterror();
    return ok;
}

void verify_file(const std::string& path, const std::string& file, int width, int height, int nch) {
    auto in = OIIO::ImageInput::open(file);
    std::string err = in ? std::string() : OIIO::geterror();
    if (!decodes(in.get(), width, height, nch, &err))
        throw std::runtime_error(write_error(path, "the encoded image does not read back" + (err.empty() ? "" : " (" + err + ")"), file));
}

// Encodes `data` (width*height*names.size() values of `type`) in the format `path`'s
// extension names, checks it decodes, and writes it with write_file (checked, atomic).
// In memory where the format's writer takes an IOProxy; otherwise through a temporary
// file in the system's temporary folder, read back.
// `as` names the format (the path itself, or "stdout.png" for standard output).
// `row0` and `full_height` (> 0): the image is that band of a taller picture, written as
// the EXR data window inside that picture's display window.
std::vector<unsigned char> encode_checked(const std::string& path, const std::string& as, int width, int height,
                                          const std::vector<std::string>& names, OIIO::TypeDesc type, const void* data, bool linear,
                                          int row0, int full_height, const std::string& picture);

void write_atomic(const std::string& path, const std::string& as, int width, int height, const std::vector<std::string>& names,
                  OIIO::TypeDesc type, const void* data, bool linear, int row0 = 0, int full_height = 0,
                  const std::string& picture = "") {
    const std::vector<unsigned char> buf = encode_checked(path, as, width, height, names, type, data, linear, row0, full_height, picture);
    write_file(path, std::string_view(reinterpret_cast<const char*>(buf.data()), buf.size()));
}

// write_atomic's encoding, decoded again: the bytes to write.
std::vector<unsigned char> encode_checked(const std::string& path, const std::string& as, int width, int height,
                                          const std::vector<std::string>& names, OIIO::TypeDesc type, const void* data, bool linear,
                                          int row0, int full_height, const std::string& picture) {
    if (width <= 0 || height <= 0) throw std::runtime_error(write_error(path, "the image is empty"));
    OIIO::ImageSpec spec(width, height, static_cast<int>(names.size()), type);
    if (full_height > 0) {
        spec.y = row0;
        spec.full_x = 0, spec.full_y = 0, spec.full_width = width, spec.full_height = full_height;
        if (!picture.empty()) spec.attribute("sdfc:picture", picture);
    }
    spec.channelnames = names;
    spec.alpha_channel = -1;
    for (size_t i = 0; i < names.size(); ++i) {
        if (names[i] == "Z") spec.z_channel = static_cast<int>(i);
        if (names[i] == "A") spec.alpha_channel = static_cast<int>(i);
    }
    // 8-bit files hold straight colour (unpremultiplied here first); float ones premultiplied.
    if (spec.alpha_channel >= 0 && !linear) spec.attribute("oiio:UnassociatedAlpha", 1);
    spec.attribute("oiio:ColorSpace", linear ? "Linear" : "sRGB");
    spec.attribute("Software", "sdfc");
    // No time of writing (OpenEXR's writer adds one unless told): the same picture is the
    // same bytes, so a re-run render (a retried farm task) is byte-identical.
    spec.attribute("DateTime", "");
    auto encode = [&](OIIO::ImageOutput& out, const std::string& name, const std::string& temp) {
        bool ok = out.open(name, spec) && out.write_image(type, data);
        std::string err = ok ? std::string() : out.geterror();
        if (!out.close() && ok) ok = false, err = out.geterror();
        if (!ok) throw std::runtime_error(write_error(path, err.empty() ? OIIO::geterror() : err, temp));
    };
    std::vector<unsigned char> buf;
    bool encoded = false;
    if (image_output_for(as)->supports("ioproxy")) {
        OIIO::Filesystem::IOVecOutput vec(buf);
        auto out = image_output_for(as, &vec);
        encode(*out, as, "");
        out.reset();
        encoded = decodes_in_memory(as, buf, width, height, int(names.size()));
    }
    if (!encoded) {
        // No writer or no reader in memory, or a broken encoding there (this OpenImageIO's
        // TIFF writer through a proxy): encoded to a file and decoded from it.
        const fs::path tmp_dir = fs::temp_directory_path();
        TempFile tmp(temp_path_for((tmp_dir / fs::path(as).filename()).string()));
        auto out = image_output_for(tmp.path());
        encode(*out, tmp.path(), tmp.path());
        out.reset();
        verify_file(path, tmp.path(), width, height, int(names.size()));
        std::ifstream in(tmp.path(), std::ios::binary);
        buf.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        if (in.bad() || buf.empty()) throw std::runtime_error(write_error(path, "cannot read back the encoded image"));
    }
    return buf;
}

// An AOV plane's EXR channel names: Z, N.x N.y N.z, steps.Y (a layer of one channel).
std::vector<std::string> aov_channel_names(const AovPlane& a) {
    if (a.name == "depth" && a.channels == 1) return {"Z"};
    if (a.name == "normal" && a.channels == 3) return {"N.x", "N.y", "N.z"};
    if (a.channels == 1) return {a.name + ".Y"};
    std::vector<std::string> names;
    for (int c = 0; c < a.channels; ++c) names.push_back(a.name + "." + "xyzw"[c % 4]);
    return names;
}

// A plane's value as stored: depth keeps +inf (a miss), anything else not finite is 0.
float stored(const AovPlane& a, float v) { return a.name == "depth" && v == INFINITY ? v : finite_or_zero(v); }

void write_side_file(const std::string& path, const Image& img, const AovPlane& a) {
    const size_t n = static_cast<size_t>(img.width) * img.height;
    if (a.data.size() < n * a.channels) throw std::runtime_error("cannot write '" + path + "': AOV '" + a.name + "' has the wrong size");
    const std::string side = aov_side_path(path, a.name);
    if (lower_ext(side) == ".exr") {  // next to a float picture: the plane's own values
        std::vector<float> buf(n * size_t(a.channels));
        for (size_t i = 0; i < buf.size(); ++i) buf[i] = stored(a, a.data[i]);
        write_atomic(side, side, img.width, img.height, aov_channel_names(a), OIIO::TypeDesc::FLOAT, buf.data(), true);
        return;
    }
    std::vector<uint8_t> px;
    std::vector<std::string> names;
    if (a.name == "normal" && a.channels == 3) {
        // Normal map convention: n * 0.5 + 0.5, stored as data (no sRGB); misses black.
        names = {"R", "G", "B"};
        px.resize(n * 3);
        for (size_t i = 0; i < n; ++i) {
            const float* v = &a.data[i * 3];
            bool miss = v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f;
            for (int c = 0; c < 3; ++c) px[i * 3 + c] = miss ? 0 : to_u8(finite_or_zero(v[c]) * 0.5f + 0.5f);
        }
    } else if (a.name == "steps" && a.channels == 1) {
        // Heat map normalised by the largest count in the image.
        names = {"R", "G", "B"};
        px.resize(n * 3);
        float mx = 0.0f;
        for (size_t i = 0; i < n; ++i) mx = std::max(mx, finite_or_zero(a.data[i]));
        for (size_t i = 0; i < n; ++i) {
            float rgb[3];
            heat_color(mx > 0 ? finite_or_zero(a.data[i]) / mx : 0.0f, rgb);
            for (int c = 0; c < 3; ++c) px[i * 3 + c] = to_u8(rgb[c]);
        }
    } else {
        // Depth (and any other single plane): normalised to the plane's range, near = white.
        names = {"Y"};
        px.resize(n);
        float lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; ++i) {
            float v = a.data[i * a.channels];
            if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
        }
        for (size_t i = 0; i < n; ++i) {
            float v = a.data[i * a.channels];
            float t = (std::isfinite(v) && hi > lo) ? 1.0f - (v - lo) / (hi - lo) : 0.0f;
            px[i] = to_u8(t);
        }
    }
    write_atomic(side, side, img.width, img.height, names, OIIO::TypeDesc::UINT8, px.data(), true);
}

// The name whose extension picks the format: the path, or for "-" (standard output)
// "stdout." and the format asked for.
std::string format_name(const std::string& path, const std::string& format) {
    if (path != "-") return path;
    if (format.empty()) throw std::runtime_error("writing an image to standard output (-o -) needs --format (png, jpg, exr, hdr, tif, ...)");
    return "stdout." + format;
}

void oiio_check_image_output(const std::string& path, const std::string& format) {
    resolve_output(path);
    const std::string as = format_name(path, format);
    (void)image_output_for(as);
    // A format outside the usual ones is tried on a small picture before any work: some
    // take no RGB at all (zfile holds one channel) and failed only after the render.
    static const char* const kUsual[] = {".png", ".jpg", ".jpeg", ".exr", ".hdr", ".tif", ".tiff", ".bmp", ".tga", ".ppm", ".pgm"};
    const std::string ext = lower_ext(as);
    if (std::find(std::begin(kUsual), std::end(kUsual), ext) != std::end(kUsual)) return;
    static std::mutex m;
    static std::vector<std::string> tried;  // (once per format: a batch checks every frame)
    std::lock_guard<std::mutex> lock(m);
    if (std::find(tried.begin(), tried.end(), ext) != tried.end()) return;
    const std::vector<uint8_t> grey(64 * 64 * 3, 128);
    (void)encode_checked(path, as, 64, 64, {"R", "G", "B"}, OIIO::TypeDesc::UINT8, grey.data(), false, 0, 0, "");
    tried.push_back(ext);
}

void write_image_and_sides(const std::string& path, const Image& img, const WriteOptions& opt, std::vector<std::string>& sides);

// A main picture that fails to write takes the side files this call wrote before it away:
// no set of new planes beside an old (or no) picture.
void oiio_write_image(const std::string& path, const Image& img, const WriteOptions& opt) {
    std::vector<std::string> sides;
    try {
        write_image_and_sides(path, img, opt, sides);
    } catch (...) {
        std::error_code ec;
        for (const std::string& side : sides) fs::remove(side, ec);
        throw;
    }
}

void write_image_and_sides(const std::string& path, const Image& img, const WriteOptions& opt, std::vector<std::string>& sides) {
    oiio_check_image_output(path, opt.format);  // before any side file: a bad main path changes nothing
    const std::string as = format_name(path, opt.format);
    const std::string ext = lower_ext(as);
    const size_t n = static_cast<size_t>(std::max(img.width, 0)) * std::max(img.height, 0);
    const int nc = std::clamp(img.channels, 1, 4);
    if (img.pixels.size() < n * img.channels) throw std::runtime_error("cannot write '" + path + "': pixel buffer has the wrong size");
    static const char* kRGBA[] = {"R", "G", "B", "A"};

    if (ext == ".exr") {
        // Linear float, AOVs as extra channels.
        std::vector<std::string> names(kRGBA, kRGBA + nc);
        if (nc == 1) names = {"Y"};
        std::vector<const AovPlane*> planes;
        for (const auto& a : img.aovs) {
            if (a.data.size() < n * a.channels) throw std::runtime_error("cannot write '" + path + "': AOV '" + a.name + "' has the wrong size");
            planes.push_back(&a);
            for (const std::string& nm : aov_channel_names(a)) names.push_back(nm);
        }
        const size_t total = names.size();
        std::vector<float> buf(n * total);
        for (size_t i = 0; i < n; ++i) {
            float* o = &buf[i * total];
            for (int c = 0; c < nc; ++c) o[c] = finite_or_zero(img.pixels[i * img.channels + c]);
            size_t k = nc;
            for (const AovPlane* a : planes)
                for (int c = 0; c < a->channels; ++c) o[k++] = stored(*a, a->data[i * a->channels + c]);
        }
        write_atomic(path, as, img.width, img.height, names, OIIO::TypeDesc::FLOAT, buf.data(), true, img.row0, img.full_height, img.picture);
        return;
    }
    if (img.full_height > 0)
        throw std::runtime_error("cannot write '" + path + "': a band of a picture (render --tiles) is written as exr, for sdfc merge");

    // Other formats: AOVs go to side files (written first: the main image appearing last
    // means the whole set is complete).
    if (opt.aov_side_files && !img.aovs.empty() && path == "-")
        throw std::runtime_error("AOV side files need a file name: write them with -o NAME, or to standard output as --format exr channels");
    if (opt.aov_side_files)
        for (const auto& a : img.aovs) {
            write_side_file(path, img, a);
            sides.push_back(aov_side_path(path, a.name));
        }

    const int oc = nc == 2 ? 1 : nc;  // no grey+alpha
    std::vector<std::string> names(kRGBA, kRGBA + oc);
    if (oc == 1) names = {"Y"};
    // Alpha goes where render --alpha on may write it (cli/main.cpp), for merge's bands and
    // the APIs' pictures too: a jpg or bmp writer would drop it, or take it for CMYK.
    if (oc == 4 && ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".tga")
        throw std::runtime_error("cannot write '" + path + "': " + ext.substr(1) + " has no alpha channel (exr, png, tif and tga have)");
    if (is_float_format(ext)) {
        const int fc = ext == ".hdr" ? 3 : oc;  // RGBE is always RGB
        std::vector<std::string> fnames(kRGBA, kRGBA + fc);
        std::vector<float> buf(n * fc);
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < fc; ++c) {
                float v = finite_or_zero(img.pixels[i * img.channels + std::min(c, oc - 1)]);
                buf[i * fc + c] = ext == ".hdr" ? std::max(v, 0.0f) : v;
            }
        write_atomic(path, as, img.width, img.height, fnames, OIIO::TypeDesc::FLOAT, buf.data(), true);
        return;
    }
    if (ext == ".pgm" && oc == 3) {
        // Grey: the luminance (Rec. 709) of the linear colour, sRGB-encoded.
        std::vector<uint8_t> grey(n);
        for (size_t i = 0; i < n; ++i) {
            const float* p = &img.pixels[i * img.channels];
            grey[i] = to_u8(linear_to_srgb(0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2]));
        }
        write_atomic(path, as, img.width, img.height, {"Y"}, OIIO::TypeDesc::UINT8, grey.data(), false);
        return;
    }
    // 8-bit, sRGB-encoded colour; alpha stays linear, and the colour straight (not
    // premultiplied by it), as PNG and the like hold it.
    std::vector<uint8_t> buf(n * oc);
    for (size_t i = 0; i < n; ++i) {
        const float a = oc == 4 ? img.pixels[i * img.channels + 3] : 1.0f;
        for (int c = 0; c < oc; ++c) {
            float v = img.pixels[i * img.channels + c];
            if (c < 3 && oc == 4) v = a > 0.0f ? v / a : 0.0f;
            buf[i * oc + c] = to_u8(c == 3 ? v : linear_to_srgb(v));
        }
    }
    write_atomic(path, as, img.width, img.height, names, OIIO::TypeDesc::UINT8, buf.data(), false);
}

Image oiio_read_image(const std::string& path) {
    // (a device or a FIFO never ends: /dev/zero kept a reader busy for good)
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);  // (one look, as SourceManager::read's)
    if (!ec && fs::exists(st) && !fs::is_regular_file(st)) throw std::runtime_error("cannot read '" + path + "': not a regular file");
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string e = OIIO::geterror();
        throw std::runtime_error("cannot read '" + path + "': " + (e.empty() ? std::string("unknown error") : e));
    }
    const OIIO::ImageSpec spec = in->spec();
    const int w = spec.width, h = spec.height, nch = spec.nchannels;
    // A data window, or a picture's hash (the only band, --tiles 0/1): a band (--tiles).
    const bool band = spec.y != 0 || spec.full_height != spec.height || !spec.get_string_attribute("sdfc:picture").empty();
    if (band && (spec.x != 0 || spec.full_x != 0 || spec.full_y != 0 || spec.full_width != w || spec.y < 0 || spec.y + h > spec.full_height))
        throw std::runtime_error("cannot read '" + path + "': its data window is not a band of whole rows of its picture");
    std::vector<float> buf(static_cast<size_t>(w) * h * nch);
    if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::FLOAT, buf.data())) {
        std::string e = in->geterror();
        throw std::runtime_error("cannot read '" + path + "': " + e);
    }
    in->close();
    const bool is_float = spec.format.basetype == OIIO::TypeDesc::FLOAT || spec.format.basetype == OIIO::TypeDesc::HALF ||
                          spec.format.basetype == OIIO::TypeDesc::DOUBLE;

    std::vector<int> colour;
    int z = -1, steps = -1, nrm[3] = {-1, -1, -1};
    for (int c = 0; c < nch; ++c) {
        const std::string nm = c < static_cast<int>(spec.channelnames.size()) ? spec.channelnames[c] : std::string();
        if (nm == "Z") z = c;
        else if (nm == "steps.Y" || nm == "steps") steps = c;
        else if (nm == "N.x") nrm[0] = c;
        else if (nm == "N.y") nrm[1] = c;
        else if (nm == "N.z") nrm[2] = c;
        else colour.push_back(c);
    }
    const size_t n = static_cast<size_t>(w) * h;
    Image img(w, h, std::max<int>(1, static_cast<int>(colour.size())));
    if (band) img.row0 = spec.y, img.full_height = spec.full_height, img.picture = spec.get_string_attribute("sdfc:picture");
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < colour.size(); ++k) {
            float v = buf[i * nch + colour[k]];
            const std::string& nm = spec.channelnames[colour[k]];
            img.pixels[i * img.channels + k] = (is_float || nm == "A") ? v : srgb_to_linear(v);
        }
    auto plane = [&](const char* name, std::initializer_list<int> chans) {
        AovPlane a{name, static_cast<int>(chans.size()), std::vector<float>(n * chans.size())};
        for (size_t i = 0; i < n; ++i) {
            int k = 0;
            for (int c : chans) a.data[i * a.channels + k++] = buf[i * nch + c];
        }
        img.aovs.push_back(std::move(a));
    };
    if (z >= 0) plane("depth", {z});
    if (nrm[0] >= 0 && nrm[1] >= 0 && nrm[2] >= 0) plane("normal", {nrm[0], nrm[1], nrm[2]});
    if (steps >= 0) plane("steps", {steps});
    return img;
}

const ImageBackend kBackend{kImageBackendVersion, oiio_write_image, oiio_check_image_output, oiio_read_image};

}  // namespace
}  // namespace sdfc

extern "C" __attribute__((visibility("default"))) const sdfc::ImageBackend* sdfc_image_backend() { return &sdfc::kBackend; }
