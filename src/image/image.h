// Float RGB images on the host and their files: PNG/JPG read (stb_image), PNG write (stb_image_write),
// EXR read/write (OpenEXR). Every writer writes to a temporary file in the target directory and
// renames it over the target, so a failure never leaves a truncated image over a good one.
// All readers and writers throw clrt::Error naming the file.
#pragma once
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace clrt {

struct ImageRGB {
    int width = 0, height = 0;
    std::vector<float> pixels;  // width*height*3, row-major, row 0 at the top
    bool isHdr = false;         // came from an EXR (float) file
    float& at(int x, int y, int c) { return pixels[(size_t(y) * width + x) * 3 + c]; }
    float at(int x, int y, int c) const { return pixels[(size_t(y) * width + x) * 3 + c]; }
};

// Reads PNG, JPG (8-bit: values 0..255, not normalised; 16-bit PNG: 0..65535) or EXR (linear floats).
// Chosen by content (magic bytes), not extension. EXR: any R,G,B channel layout (A ignored), half or
// float, scanline or tiled, every compression; NaN/Inf/negative texels are replaced by 0 with one
// warning that counts them. Grey images are expanded to RGB.
ImageRGB readImage(const std::string& path);

// Writes an 8-bit RGB PNG of already-quantised values (0..255 per channel, row 0 at the top).
void writePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);

// Writes a PNG from linear values: clamp to [0,255] and round (truncate = true: floor, which is what
// the course's reference renders do; see README "Conventions").
void writePngClamped(const std::string& path, const ImageRGB& img, bool truncate = false);

struct ExrWriteOptions {
    bool half = false;                            // HALF instead of FLOAT channels
    std::map<std::string, std::string> attributes; // extra string header attributes (renderer, spp, ...)
};
void writeExr(const std::string& path, const ImageRGB& img, const ExrWriteOptions& opts = {});

// Writes `path` via a temporary sibling file and rename(); `writer` receives the temporary path.
// Throws clrt::Error (ExitCode::Output) if the directory does not exist or is not writable.
template <class F> void writeAtomically(const std::string& path, F writer);
std::string temporarySiblingPath(const std::string& path);
void commitTemporary(const std::string& tmpPath, const std::string& path);

template <class F> void writeAtomically(const std::string& path, F writer) {
    std::string tmp = temporarySiblingPath(path);
    try {
        writer(tmp);
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
    commitTemporary(tmp, path);
}

}  // namespace clrt
