// The stb_image / stb_image_write implementations, compiled into the fuzz targets with the fuzzer's
// instrumentation (the CMake build links Debian's prebuilt libstb instead).
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
