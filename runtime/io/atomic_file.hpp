// Writing output files safely: into a temporary file in the target's folder, then renamed
// over the target, so a crash or a kill never leaves a partial file behind and an existing
// output is replaced only by a complete one.
#pragma once
#include <functional>
#include <string>

namespace sdfc {

// A temporary path beside `target` that keeps its extension (so format detection by
// extension still works): "dir/out.png" -> "dir/.out.tmp-<pid>-<n>.png".
std::string temp_path_for(const std::string& target);

// Calls write(temp) and renames temp onto target; removes temp and rethrows on failure.
void write_atomically(const std::string& target, const std::function<void(const std::string& temp)>& write);

// Text (GLSL, HTML) through write_atomically. Throws std::runtime_error on failure.
void write_text_file(const std::string& path, const std::string& text);

}  // namespace sdfc
