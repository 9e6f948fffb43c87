// The external corpus of models in ../shared/bench/vm (public Prospero/Fidget models), for
// the tests that read them: each skips, with a warning, where ../shared is absent.
#pragma once
#include <catch2/catch.hpp>

#include <filesystem>
#include <memory>
#include <string>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"

namespace sdfc::test {

struct SharedModel {
    SourceManager sm;  // (the compiled scene's locations point into it)
    CompiledScene cs;
};

// The model `name` (e.g. "prospero.vm") loaded and compiled; null, with a warning, when the
// corpus is not there.
inline std::unique_ptr<SharedModel> shared_model(const std::string& name) {
    const std::filesystem::path path = std::filesystem::path(SDFC_SHARED_DIR) / "bench" / "vm" / name;
    if (!std::filesystem::exists(path)) {
        WARN("skipped: " << path << " is absent");
        return nullptr;
    }
    auto m = std::make_unique<SharedModel>();
    m->cs = compile_scene(load_scene(m->sm, path.string()));
    return m;
}

}  // namespace sdfc::test
