// image_size.h — the size an image file declares, read from its header alone (for estimating memory
// before images are decoded: flatten/memory_estimate.cpp). Defined in image_io.cpp.
#pragma once
#include <string>

namespace clrt {
// The width and height an image file declares in its header (PNG IHDR, JPEG start of frame, EXR data
// window), without decoding it; false when the file cannot be read or is none of those formats.
bool readImageSize(const std::string& path, int& width, int& height);
}  // namespace clrt
