// Keeping Mesa's DRI driver loaded past eglTerminate, for every test that draws through EGL
// (gles.hpp's GLES contexts, test_gl330.cpp's desktop one).
#pragma once
#include <dlfcn.h>
#include <link.h>

#include <cstring>
#include <string>
#include <vector>

namespace sdfc::gpu_test {

// Keeps Mesa's DRI driver (swrast_dri.so, loaded by eglInitialize) in memory after
// eglTerminate unloads it. The driver's globals hold a few small allocations to the end of
// the process; once it is unmapped, LeakSanitizer (.ci/sanitize) sees them as leaks from an
// unknown module, which no suppression can name. Loaded, they stay reachable.
inline void keep_dri_driver_loaded() {
    std::vector<std::string> drivers;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
            if (info->dlpi_name && std::strstr(info->dlpi_name, "_dri.so"))
                static_cast<std::vector<std::string>*>(out)->push_back(info->dlpi_name);
            return 0;
        },
        &drivers);
    for (const auto& d : drivers) dlopen(d.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);  // no handle kept: it stays
}

}  // namespace sdfc::gpu_test
