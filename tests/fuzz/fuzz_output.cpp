// libFuzzer target over the output path (issue 14): write_image and write_file into a small
// tmpfs that the input fills to a chosen level, onto a new file, an existing one, a symlink,
// a dangling symlink, a directory, a device node or a long name. A finding is: a write that
// fails without `cannot write 'PATH': REASON` or names a temporary file, a failure that
// changed the existing output or the kind of node, a success whose file does not decode,
// a temporary file left behind, or a crash or sanitizer report.
//
// Build (clang only):  CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DSDFC_FUZZ=ON \
//                        -DSDFC_BUILD_TESTS=OFF && cmake --build build-fuzz --target fuzz_output
// Run (as root, for the tmpfs and the device nodes; a plain folder otherwise; a TMPDIR of
// its own keeps the scan for stray temporary files short):
//                      mkdir -p /tmp/fz && TMPDIR=/tmp/fz build-fuzz/fuzz_output -max_total_time=600
//                      (libFuzzer ends with _Exit: umount /tmp/fz/sdfc-fuzz-out-* afterwards)
#include <fcntl.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "runtime/io/atomic_file.hpp"
#include "runtime/io/image.hpp"

namespace fs = std::filesystem;

namespace {

const std::string& dir() {
    static std::string d = [] {
        std::string p = (fs::temp_directory_path() / ("sdfc-fuzz-out-" + std::to_string(::getpid()))).string();
        fs::create_directories(p);
        if (::mount("tmpfs", p.c_str(), "tmpfs", 0, "size=256k") != 0) std::fprintf(stderr, "fuzz_output: no tmpfs, a plain folder\n");
        return p;
    }();
    return d;
}

std::string slurp(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "fuzz_output finding: %s\n", what.c_str());
    std::abort();
}

unsigned kind_of(const std::string& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 ? unsigned(st.st_mode & S_IFMT) : 0u;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 6) return 0;
    const std::string& d = dir();
    for (const auto& e : fs::directory_iterator(d)) fs::remove_all(e.path());
    static const char* kExt[] = {".png", ".jpg", ".exr", ".hdr", ".tif", ".bmp", ".tga", ".txt", ".foo", ""};
    const int node = data[0] % 8, ext_i = data[1] % 10;
    const int w = 1 + data[2] % 64, h = 1 + data[3] % 64;
    const size_t free_left = size_t(data[4]) * 1024;  // bytes the file system keeps free
    std::string stem;
    for (size_t i = 6; i < size && stem.size() < 300; ++i) {
        char c = char(data[i]);
        if (c != '/' && c != '\0') stem += c;
    }
    if (node == 7) stem.assign(size_t(data[5]) + 1, 'n');  // a long name (over 255: ENAMETOOLONG)
    if (stem.empty() || stem == "." || stem == ".." || stem.find(".tmp-") != std::string::npos) stem = "out";
    const std::string path = d + "/" + stem + kExt[ext_i];
    const std::string target = d + "/target" + kExt[ext_i];
    const bool text = ext_i == 7;
    // The node at `path` before the write.
    switch (node) {
        case 1: std::ofstream(path, std::ios::binary) << "old output"; break;
        case 2: std::ofstream(target, std::ios::binary) << "old target"; ::symlink(("target" + std::string(kExt[ext_i])).c_str(), path.c_str()); break;
        case 3: ::symlink("missing-target", path.c_str()); break;
        case 4: fs::create_directories(path); break;
        case 5: ::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, 3)); break;  // a null device
        case 6: ::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, 7)); break;  // a full device
        default: break;
    }
    // Fill the file system to leave `free_left` bytes.
    struct statvfs vfs {};
    if (::statvfs(d.c_str(), &vfs) == 0) {
        const double avail = double(vfs.f_bavail) * double(vfs.f_frsize);
        if (avail > double(free_left) && avail < 64.0 * 1024 * 1024) {
            int fd = ::open((d + "/filler").c_str(), O_WRONLY | O_CREAT, 0644);
            std::string block(4096, 'x');
            for (double left = avail - double(free_left); fd >= 0 && left > 0; left -= 4096)
                if (::write(fd, block.data(), size_t(std::min(left, 4096.0))) <= 0) break;
            if (fd >= 0) ::close(fd);
        }
    }
    const unsigned kind_before = kind_of(path);
    const std::string real = node == 2 ? target : path;
    const std::string before = kind_before == S_IFREG || node == 2 ? slurp(real) : std::string();
    sdfc::Image img(w, h);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(data[(i + 6) % size]) / 255.0f;
    const std::string content = "text " + std::to_string(w) + "\n";
    bool ok = true;
    std::string err;
    try {
        if (text) sdfc::write_text_file(path, content);
        else sdfc::write_image(path, img, sdfc::WriteOptions{false});
    } catch (const std::exception& e) {
        ok = false;
        err = e.what();
    }
    if (kind_of(path) != kind_before && !(kind_before == 0 && ok)) finding("the node changed kind: " + path + " " + err);
    if (!ok) {
        if (err.rfind("cannot write '" + path + "': ", 0) != 0) finding("message: " + err);
        if (err.find(".tmp-") != std::string::npos) finding("names a temporary file: " + err);
        if ((kind_before == S_IFREG || node == 2) && slurp(real) != before) finding("a failure changed the output: " + err);
    } else if (node != 5 && node != 6 && node != 4) {
        if (text) {
            if (slurp(real == path && node == 3 ? d + "/missing-target" : real) != content) finding("text differs");
        } else {
            const std::string file = node == 3 ? d + "/missing-target" : real;
            try {
                // Through a plain name (OpenImageIO refuses a name that is not UTF-8), off the
                // full file system.
                const std::string copy = (fs::temp_directory_path() / ("readback-" + std::to_string(::getpid()) + kExt[ext_i])).string();
                std::ofstream(copy, std::ios::binary) << slurp(file);
                if (sdfc::read_image(copy).width != w) finding("wrong width");
            } catch (const std::exception& e) {
                finding(std::string("a written image does not read: ") + e.what());
            }
        }
    } else if (node == 6 || node == 4) {
        finding("a write onto a full device or a directory succeeded");
    }
    for (const auto& e : fs::directory_iterator(d))
        if (e.path().filename().string().find(".tmp-") != std::string::npos) finding("temporary file left: " + e.path().string());
    for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
        if (e.path().filename().string().rfind(".", 0) == 0 && e.path().filename().string().find(".tmp-" + std::to_string(::getpid()) + "-") != std::string::npos)
            finding("temporary file left in the temporary folder: " + e.path().string());
    return 0;
}
