#include "runtime/io/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace sdfc {

std::string temp_path_for(const std::string& target) {
    static std::atomic<unsigned> counter{0};
    namespace fs = std::filesystem;
    fs::path t(target);
    std::string name = "." + t.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                       std::to_string(counter++) + t.extension().string();
    return (t.parent_path() / name).string();
}

void write_atomically(const std::string& target, const std::function<void(const std::string&)>& write) {
    std::string tmp = temp_path_for(target);
    try {
        write(tmp);
        if (std::rename(tmp.c_str(), target.c_str()) != 0)
            throw std::runtime_error("cannot write '" + target + "': " + std::strerror(errno));
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
}

void write_text_file(const std::string& path, const std::string& text) {
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        if (!out) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
        out.close();
        if (!out) throw std::runtime_error("cannot write '" + path + "': write failed");
    });
}

}  // namespace sdfc
