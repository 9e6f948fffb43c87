#include "cli/args.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "compiler/base/names.hpp"

namespace sdfc::cli {

void Args::declare(std::vector<std::string> names) {
    known_ = std::move(names);
    declared_ = true;
}

void Args::ask(const std::string& name) {
    if (!declared_) {
        known_.push_back(name);
        return;
    }
    if (std::find(known_.begin(), known_.end(), name) == known_.end())
        throw std::logic_error(fmt::format("internal: the option {} is read but not in the option table (cli/options.cpp)", name));
}

bool Args::flag(const std::string& name) {
    ask(name);
    bool found = false;
    for (size_t i = 0; i < end_; ++i)
        if (!used_[i] && args_[i] == name) used_[i] = found = true;
    return found;
}

std::optional<std::string> Args::value(const std::string& name, const std::string& alt) {
    ask(name);
    if (!alt.empty()) ask(alt);
    std::optional<std::string> v;
    for (size_t i = 0; i < end_; ++i) {
        if (used_[i]) continue;
        const std::string& a = args_[i];
        for (const std::string& n : {name, alt}) {
            if (n.empty()) continue;
            if (a == n) {
                if (i + 1 >= end_) throw UsageError(fmt::format("{} needs a value", n));
                used_[i] = used_[i + 1] = true;
                v = args_[i + 1];
                ++i;
                break;
            }
            if (a.rfind(n + "=", 0) == 0) {
                used_[i] = true;
                v = a.substr(n.size() + 1);
                break;
            }
        }
    }
    return v;
}

std::vector<std::string> Args::values(const std::string& name) {
    ask(name);
    std::vector<std::string> out;
    for (size_t i = 0; i < end_; ++i) {
        if (used_[i]) continue;
        const std::string& a = args_[i];
        if (a == name) {
            if (i + 1 >= end_) throw UsageError(fmt::format("{} needs a value", name));
            used_[i] = used_[i + 1] = true;
            out.push_back(args_[++i]);
        } else if (a.size() > name.size() && a.rfind(name, 0) == 0) {
            used_[i] = true;
            out.push_back(a.substr(name.size()));
        }
    }
    return out;
}

std::vector<std::string> Args::positionals() {
    std::vector<std::string> out;
    for (size_t i = 0; i < args_.size(); ++i) {
        if (used_[i]) continue;
        const std::string& a = args_[i];
        if (i < end_ && a.size() > 1 && a[0] == '-' && !std::isdigit(static_cast<unsigned char>(a[1])) && a[1] != '.') {
            // (no guess for a one-letter option: any other one is as near)
            const std::string near = a.size() <= 2 ? std::string() : nearest_name(a.substr(0, a.find('=')), known_);
            throw UsageError(near.empty() ? fmt::format("unknown option '{}' (see --help)", a)
                                          : fmt::format("unknown option '{}' (did you mean `{}`?)", a, near));
        }
        out.push_back(args_[i]);
    }
    return out;
}

int Args::to_int(const std::string& flag, const std::string& v, long lo, long hi) {
    char* end = nullptr;
    long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0') throw UsageError(fmt::format("{} takes a whole number, not '{}'", flag, v));
    if (x < lo || x > hi) throw UsageError(fmt::format("{} must be from {} to {}, not {}", flag, lo, hi, v));  // (as typed: strtol clamps)
    return static_cast<int>(x);
}

float Args::to_float(const std::string& flag, const std::string& v) {
    char* end = nullptr;
    float x = std::strtof(v.c_str(), &end);
    if (v.empty() || *end != '\0') throw UsageError(fmt::format("{} takes a number, not '{}'", flag, v));
    // (a number past a float's range is named as such, not as no number, or as 0 where it underflows)
    const double d = std::strtod(v.c_str(), nullptr);
    if (std::isfinite(d) && (!std::isfinite(x) || (x == 0.0f && d != 0.0)))
        throw UsageError(fmt::format("{} {}: the number is {} for a float (sdfc computes in floats)", flag, v, x == 0.0f ? "too small" : "too large"));
    if (!std::isfinite(x)) throw UsageError(fmt::format("{} takes a number, not '{}'", flag, v));
    return x;
}

std::vector<float> Args::to_floats(const std::string& flag, const std::string& v, size_t n) {
    std::vector<float> out;
    size_t start = 0;
    while (start <= v.size()) {
        size_t comma = v.find(',', start);
        std::string part = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        out.push_back(to_float(flag, part));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (out.size() != n) throw UsageError(fmt::format("{} takes {} comma-separated numbers, not '{}'", flag, n, v));
    return out;
}

}  // namespace sdfc::cli
