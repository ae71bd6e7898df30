// libFuzzer target: readImage (PNG, JPEG, EXR by magic bytes) on arbitrary bytes. clrt::Error is
// accepted; anything else is a bug. An image that loads must be consistent and hold no NaN/Inf
// (EXR texels are sanitised).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz_common.h"
#include "image/image.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string path = clrt::fuzz::writeInput(data, size, "image.bin");
    try {
        clrt::ImageRGB img = clrt::readImage(path);
        if (img.width <= 0 || img.height <= 0) std::abort();
        if (img.pixels.size() != size_t(img.width) * size_t(img.height) * 3) std::abort();
        if (img.isHdr)
            for (float v : img.pixels)
                if (!std::isfinite(v)) std::abort();
    } catch (const clrt::Error&) {
    }
    return 0;
}
