// One entry point for every command that takes a scene: a .sdf script or a .vm model
// (the Prospero/Fidget flat SSA format, LANGUAGE.md section 10).
#pragma once
#include <string>

#include "lang/interpreter.hpp"

namespace sdfc {

bool is_vm_path(const std::string& path);

// A .vm model as a raw field (root = Field shape); is_2d when it reads only var-x/var-y.
Scene load_vm(SourceManager& sm, const SourceFile& file);

Scene load_scene(SourceManager& sm, const std::string& path, const InterpretOptions& opts = {});

}  // namespace sdfc
