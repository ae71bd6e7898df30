// src/image/: images on the host (PNG/JPG/EXR read and write, the tone-mapping reference).
// Float RGB images on the host and their files: PNG/JPG read (stb_image), PNG write (own encoder on
// zlib, image_write.cpp), EXR read/write (OpenEXR). Every writer writes to a temporary file in the target directory and
// renames it over the target, so a failure never leaves a truncated image over a good one; the
// *Uncommitted forms stop before the rename, for callers that commit several files together.
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
// Images of more than kMaxImageTexels (16384x8192) are refused from their header, before decoding.
ImageRGB readImage(const std::string& path);
constexpr long long kMaxImageTexels = 16384LL * 8192LL;

// Writes an 8-bit RGB PNG of already-quantised values (0..255 per channel, row 0 at the top).
// Per row the PNG filter with the smallest sum of |residual| (as stb_image_write and libpng choose),
// then zlib with its run-length strategy (Z_RLE: fast, and smaller than stb_image_write's output on
// renders; very compressible images are also tried at zlib's default level, keeping the smaller).
void writePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);
// The PNG file's bytes, as writePng8 writes them (`path` only names the image in errors).
std::string encodePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);

// Writes a PNG from linear values: clamp to [0,255] and round (truncate = true: floor, which is what
// the course's reference renders do; see README "Conventions").
void writePngClamped(const std::string& path, const ImageRGB& img, bool truncate = false);

struct ExrWriteOptions {
    bool half = false;                            // HALF instead of FLOAT channels
    std::map<std::string, std::string> attributes; // extra string header attributes (renderer, spp, ...)
};
// Single-part scanline RGB OpenEXR (OpenEXR's writer), ZIP compression, FLOAT or HALF channels, plus
// string attributes; compressed on OpenEXR's thread pool (all cores).
void writeExr(const std::string& path, const ImageRGB& img, const ExrWriteOptions& opts = {});

// writePng8 / writeExr up to the rename: the complete file is left in the returned temporary sibling
// of `path`, which the caller renames with commitTemporary(tmp, path) or deletes. On failure nothing
// is left behind and clrt::Error names `path`. Safe to call from several threads at once.
std::string writePng8Uncommitted(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);
std::string writeExrUncommitted(const std::string& path, const ImageRGB& img, const ExrWriteOptions& opts = {});

// Writes `path` via a temporary sibling file and rename(); `writer` receives the temporary path, an
// empty file already created (exclusively, never through a symlink), which it opens with
// openTemporaryForWrite or by name. Throws clrt::Error (ExitCode::Output) if the directory does not
// exist or is not writable. rename() replaces a final symlink itself: nothing is written through it.
// writeTemporary stops before the rename and returns the temporary path (see above).
template <class F> void writeAtomically(const std::string& path, F writer);
template <class F> std::string writeTemporary(const std::string& path, F writer);
// The temporary sibling's name: dir/.NAME.tmp-PID.
std::string temporarySiblingPath(const std::string& path);
// Creates the (empty) temporary sibling of `path` and records it; returns its path.
std::string createTemporary(const std::string& path);
// Opens a temporary made by createTemporary for writing (truncated; O_NOFOLLOW); returns the fd.
int openTemporaryForWrite(const std::string& tmpPath, const std::string& path);
// Renames a recorded temporary over `path` (on failure it is removed and clrt::Error names `path`).
void commitTemporary(const std::string& tmpPath, const std::string& path);
// Removes a recorded temporary (failed writes).
void discardTemporary(const std::string& tmpPath);
// Removes every temporary not yet committed or discarded and blocks any further create, commit or
// discard for good: for a process about to _exit (the CLI's second Ctrl-C), so that no temporary
// file is left behind. Safe to call from any thread (not from a signal handler).
void removeTemporariesForExit();
// OpenEXR's global thread pool sized to the machine, once (readers and writers).
void initExrThreads();

template <class F> std::string writeTemporary(const std::string& path, F writer) {
    std::string tmp = createTemporary(path);
    try {
        writer(tmp);
    } catch (...) {
        discardTemporary(tmp);
        throw;
    }
    return tmp;
}

template <class F> void writeAtomically(const std::string& path, F writer) {
    commitTemporary(writeTemporary(path, writer), path);
}

}  // namespace clrt
