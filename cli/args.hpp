// A small command-line reader: flags with values, repeated positionals, and errors in the
// same `sdfc: error:` form as everything else.
#pragma once
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sdfc::cli {

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class Args {
public:
    Args(std::vector<std::string> a) : args_(std::move(a)), used_(args_.size(), false) {
        end_ = args_.size();
        for (size_t i = 0; i < args_.size(); ++i)
            if (args_[i] == "--") {
                end_ = i;
                used_[i] = true;
                break;
            }
    }

    // The options the command takes (its row of the option table): asking for another is a
    // bug in sdfc (std::logic_error), and did-you-mean picks among them all.
    void declare(std::vector<std::string> names);

    bool flag(const std::string& name);  // --name (no value)
    std::optional<std::string> value(const std::string& name, const std::string& alt = "");  // --name V or --name=V
    // Every value of a short option that may repeat: -D V, -DV.
    std::vector<std::string> values(const std::string& name);
    // Everything not consumed (call last): an unknown option is an error naming the nearest
    // option this command asked for; after `--` every argument is a positional.
    std::vector<std::string> positionals();

    static int to_int(const std::string& flag, const std::string& v, long lo, long hi);
    static float to_float(const std::string& flag, const std::string& v);
    static std::vector<float> to_floats(const std::string& flag, const std::string& v, size_t n);

private:
    std::vector<std::string> args_;
    std::vector<bool> used_;
    void ask(const std::string& name);  // a name the command reads: known, and declared
    std::vector<std::string> known_;  // the options asked for (or declared), for did-you-mean
    bool declared_ = false;
    size_t end_ = 0;                  // options end here (at `--`, or the end)
};

}  // namespace sdfc::cli
