// PSNR of two pictures over their 8-bit sRGB values (as written to .png):
//   sdfc_psnr A B [DIFF]   prints `psnr=… pixels_off=…` (inf when identical; -1 when the
//                          sizes differ; pixels_off: pixels with a channel off by more than 8
//                          levels); DIFF: an image of |A - B| x 8 to see where they differ
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>

#include "runtime/io/image.hpp"

using namespace sdfc;

namespace {
int to_u8(float linear) {
    const float v = linear_to_srgb(linear);
    if (!(v > 0.0f)) return 0;
    if (v >= 1.0f) return 255;
    return int(v * 255.0f + 0.5f);
}
}  // namespace

int main(int argc, char** argv) {
    if (argc != 3 && argc != 4) {
        std::fprintf(stderr, "usage: sdfc_psnr A B [DIFF]\n");
        return 2;
    }
    const Image a = read_image(argv[1]), b = read_image(argv[2]);
    if (a.width != b.width || a.height != b.height) {
        std::printf("psnr=-1\n");
        return 0;
    }
    double se = 0;
    size_t n = 0, off = 0;
    Image diff(a.width, a.height, 3);
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            int worst = 0;
            for (int c = 0; c < 3; ++c) {
                const int d = to_u8(a.at(x, y, c < a.channels ? c : a.channels - 1)) -
                              to_u8(b.at(x, y, c < b.channels ? c : b.channels - 1));
                se += double(d) * d;
                ++n;
                worst = std::max(worst, std::abs(d));
                diff.at(x, y, c) = std::min(1.0f, float(std::abs(d)) * 8.0f / 255.0f);
            }
            off += worst > 8;
            if (worst > 64 && std::getenv("SDFC_PSNR_LIST")) std::printf("pixel %d %d off by %d\n", x, y, worst);
        }
    if (se == 0) std::printf("psnr=inf pixels_off=0\n");
    else std::printf("psnr=%.2f pixels_off=%zu\n", 10.0 * std::log10(255.0 * 255.0 / (se / double(n))), off);
    if (argc == 4) write_image(argv[3], diff);
    return 0;
}
