// Output names of render (and slice): the placeholders {frame:04d}, {frame} and {name}.
#pragma once
#include <string>
#include <vector>

namespace sdfc::cli {

// What `{name}` stands for: the scene file's name without its folder and extension,
// "stdin" for a script read from standard input.
std::string scene_name(const std::string& path);

// `{frame:04d}`, `{frame}` and `{name}` in an output path; `{{` and `}}` stand for a brace.
// Any other `{...}`, or a brace left open, is a UsageError (a typo would otherwise send every
// frame to one file).
std::string expand(const std::string& out, int frame, const std::string& name);

// A UsageError when two of the pictures (each scene's frames f0..f1), or their side files of
// `side_aovs` (outside EXR), would be written to one file: the second would replace the first.
void check_distinct_outputs(const std::string& out, const std::vector<std::string>& scenes, int f0, int f1,
                            const std::vector<std::string>& side_aovs = {});

}  // namespace sdfc::cli
