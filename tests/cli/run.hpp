// Running the sdfc binary from tests: exit status, stdout and stderr.
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace sdfc::test {

struct RunResult {
    int status = -1;
    std::string out, err;
};

inline std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

inline std::string temp_dir() {
    static std::string dir = [] {
        std::string d = (std::filesystem::temp_directory_path() / ("sdfc-cli-" + std::to_string(::getpid()))).string();
        // Empty: a process that had this pid before may have left files (pids wrap), and
        // tests check that a failed command wrote none.
        std::filesystem::remove_all(d);
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

inline std::string write_temp(const std::string& name, const std::string& text) {
    std::string p = temp_dir() + "/" + name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
}

// Runs `sdfc ARGS` (a shell-quoted string) and captures everything; `env` ("NAME=value
// ...") goes before the command; `input` (a file) is its standard input.
inline RunResult run_sdfc(const std::string& args, const std::string& env = "", const std::string& input = "/dev/null") {
    const char* bin = std::getenv("SDFC_BIN");  // override: test another build of sdfc
    std::string exe = bin ? bin : SDFC_BIN_PATH;
    std::string out = temp_dir() + "/stdout.txt", err = temp_dir() + "/stderr.txt";
    std::string cmd = env + (env.empty() ? "" : " ") + "'" + exe + "' " + args + " >'" + out + "' 2>'" + err + "' <'" + input + "'";
    int st = std::system(cmd.c_str());
    RunResult r;
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

inline std::string example(const std::string& name) { return std::string(SDFC_SOURCE_DIR) + "/examples/" + name; }

}  // namespace sdfc::test
