// sdfc's modules: libraries opened on first use, so that start-up does not pay for what a
// command does not need (libsdfc_image.so: OpenImageIO; libsdfc_preview.so: the preview's
// HTTP server with its TLS and compression libraries).
#pragma once
#include <string>

namespace sdfc {

// The address of `entry` in the module `file`: looked for next to the executable (the build
// folder), one folder up when that is a build folder (a test in build/tests), or in
// ../lib/sdfc beside an installed bin/;
// the environment variable `env`, if set, names the file instead. nullptr, with `failure`
// saying why ("not found (looked for ...)", the loader's error, or "not this build's ..."),
// when it cannot be opened.
void* module_entry(const char* file, const char* env, const char* entry, std::string& failure);

}  // namespace sdfc
