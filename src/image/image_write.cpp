// Writing image files (see image.h). PNG on zlib: per row the best of the five PNG filters, then
// zlib's run-length strategy (stb_image_write, used before, took ~0.2 s for a 1500x833 image and made
// larger files); EXR with OpenEXR, through an fd. Every writer goes through writeTemporary: a
// temporary sibling created exclusively (never through a symlink) and recorded, so that
// removeTemporariesForExit can delete whatever is in flight when the process is interrupted; the
// *Uncommitted forms stop there, the others rename it over the target. Kept apart from image_io.cpp
// so that the fuzz targets, which compile that file alone, need no zlib.
#include "image/image.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <Imath/half.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

namespace {

// ---- temporary files ---------------------------------------------------------------------------

// The temporaries created and not yet committed or discarded. The mutex is held across each open,
// rename and unlink, so removeTemporariesForExit (which keeps it locked for good) sees every file
// that exists and no new one can appear after it.
std::mutex gTempMutex;
std::set<std::string> gTemps;

// Writes all of data[0..n) to fd; false with errno on failure.
bool writeAll(int fd, const char* data, size_t n) {
    while (n > 0) {
        const ssize_t w = ::write(fd, data, n);
        if (w < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        data += w;
        n -= size_t(w);
    }
    return true;
}

// Deflates in[0..n) into `out` (resized to fit) as one zlib stream; false on a zlib failure.
// Z_RLE (matches at distance 1 only) runs 2-4 times faster than zlib's LZ77 matching and is as good
// or better on noisy renders, but much worse on flat or repetitive content, where matching is fast.
bool zlibDeflate(const unsigned char* in, size_t n, int level, int strategy, std::vector<unsigned char>& out) {
    z_stream zs{};
    if (deflateInit2(&zs, level, Z_DEFLATED, 15, 8, strategy) != Z_OK) return false;
    out.resize(deflateBound(&zs, uLong(n)));
    zs.next_in = const_cast<Bytef*>(in);
    zs.next_out = out.data();
    int rc = Z_OK;
    while (rc == Z_OK) {  // avail_in / avail_out are 32-bit: at most 1 GiB at a time
        const size_t inLeft = n - size_t(zs.next_in - in), outLeft = out.size() - size_t(zs.next_out - out.data());
        zs.avail_in = uInt(std::min<size_t>(inLeft, size_t(1) << 30));
        zs.avail_out = uInt(std::min<size_t>(outLeft, size_t(1) << 30));
        rc = deflate(&zs, zs.avail_in == inLeft ? Z_FINISH : Z_NO_FLUSH);
    }
    out.resize(size_t(zs.next_out - out.data()));
    deflateEnd(&zs);
    return rc == Z_STREAM_END;
}

// ---- PNG encoding ------------------------------------------------------------------------------

void putBigEndian32(std::string& out, uint32_t v) {
    const char b[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    out.append(b, 4);
}

// Appends one PNG chunk: length, type, data, CRC-32 of type and data.
void putPngChunk(std::string& out, const char type[4], const unsigned char* data, size_t size) {
    putBigEndian32(out, uint32_t(size));
    const size_t start = out.size();
    out.append(type, 4);
    out.append(reinterpret_cast<const char*>(data), size);
    putBigEndian32(out, uint32_t(crc32_z(0, reinterpret_cast<const Bytef*>(out.data() + start), size + 4)));
}

int paethPredictor(int a, int b, int c) {
    const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// Residuals of one row under the predictor pred(left, up, upper-left) into out; returns the sum of
// |residual as a signed byte|. Bytes of the first pixel have no left neighbours (0). The main loop
// has no branches and no aliasing (restrict), so the compiler vectorises it.
template <class Pred>
long filterPngRowWith(const unsigned char* __restrict row, const unsigned char* __restrict prev, size_t n, size_t bpp,
                      unsigned char* __restrict out, Pred pred) {
    long cost = 0;
    const size_t head = std::min(bpp, n);
    for (size_t i = 0; i < head; ++i) {
        out[i] = static_cast<unsigned char>(row[i] - pred(0, prev[i], 0));
        cost += std::abs(int(static_cast<signed char>(out[i])));
    }
    for (size_t i = head; i < n; ++i) {
        const unsigned char r = static_cast<unsigned char>(row[i] - pred(row[i - bpp], prev[i], prev[i - bpp]));
        out[i] = r;
        cost += std::abs(int(static_cast<signed char>(r)));
    }
    return cost;
}

// Filters one row of `n` bytes (`bpp` bytes per pixel; `prev` is the row above, zeros for the first
// row) into out[0] = filter type, out[1..n] = residuals, choosing of PNG's five filters the one with
// the smallest sum of |residual as a signed byte| (libpng's and stb_image_write's heuristic).
void filterPngRow(const unsigned char* row, const unsigned char* prev, size_t n, size_t bpp, unsigned char* out,
                  std::vector<unsigned char>& scratch) {
    scratch.resize(n);
    unsigned char* best = out + 1;  // the best residuals so far live here
    unsigned char* trial = scratch.data();
    long bestCost = -1;
    auto consider = [&](int type, long cost) {
        if (bestCost >= 0 && cost >= bestCost) return;
        bestCost = cost;
        out[0] = static_cast<unsigned char>(type);
        std::memcpy(best, trial, n);
    };
    consider(0, filterPngRowWith(row, prev, n, bpp, trial, [](int, int, int) { return 0; }));
    consider(1, filterPngRowWith(row, prev, n, bpp, trial, [](int a, int, int) { return a; }));
    consider(2, filterPngRowWith(row, prev, n, bpp, trial, [](int, int b, int) { return b; }));
    consider(3, filterPngRowWith(row, prev, n, bpp, trial, [](int a, int b, int) { return (a + b) >> 1; }));
    consider(4, filterPngRowWith(row, prev, n, bpp, trial, paethPredictor));
}

void checkImage(const std::string& path, int width, int height, size_t size) {
    if (width <= 0 || height <= 0 || size != size_t(width) * size_t(height) * 3)
        throw Error(path + ": cannot write an image of " + std::to_string(width) + "x" + std::to_string(height) +
                        " with " + std::to_string(size) + " values",
                    ExitCode::Output);
}

}  // namespace

std::string encodePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
    checkImage(path, width, height, rgb.size());
    const size_t stride = size_t(width) * 3;
    std::vector<unsigned char> filtered((stride + 1) * size_t(height)), zeros(stride), scratch;
    for (int y = 0; y < height; ++y) {
        const unsigned char* row = rgb.data() + size_t(y) * stride;
        filterPngRow(row, y > 0 ? row - stride : zeros.data(), stride, 3, filtered.data() + size_t(y) * (stride + 1),
                     scratch);
    }

    // Z_RLE (see zlibDeflate), zlib's strategy for filtered image rows; images it shrinks below 1/8
    // (flat or synthetic content, where matching is fast and gains most) are also deflated at zlib's
    // default level, keeping the smaller.
    std::vector<unsigned char> idat, alt;
    bool ok = zlibDeflate(filtered.data(), filtered.size(), Z_BEST_SPEED, Z_RLE, idat);
    if (ok && idat.size() * 8 < filtered.size()) {
        ok = zlibDeflate(filtered.data(), filtered.size(), Z_DEFAULT_COMPRESSION, Z_DEFAULT_STRATEGY, alt);
        if (ok && alt.size() < idat.size()) idat.swap(alt);
    }
    if (!ok) throw Error(path + ": cannot write PNG: zlib compression failed", ExitCode::Output);
    const size_t zsize = idat.size();

    std::string png("\x89PNG\r\n\x1a\n", 8);
    unsigned char ihdr[13];
    const uint32_t dims[2] = {uint32_t(width), uint32_t(height)};
    for (int k = 0; k < 2; ++k)
        for (int b = 0; b < 4; ++b) ihdr[4 * k + b] = static_cast<unsigned char>(dims[k] >> (24 - 8 * b));
    ihdr[8] = 8;   // bit depth
    ihdr[9] = 2;   // colour type: RGB
    ihdr[10] = 0;  // compression: deflate
    ihdr[11] = 0;  // filter method: adaptive, five types
    ihdr[12] = 0;  // no interlace
    putPngChunk(png, "IHDR", ihdr, sizeof ihdr);
    constexpr size_t kMaxIdat = size_t(1) << 24;  // several IDAT chunks for very large images
    for (size_t off = 0; off < zsize || off == 0; off += kMaxIdat)
        putPngChunk(png, "IDAT", idat.data() + off, std::min(kMaxIdat, zsize - off));
    putPngChunk(png, "IEND", nullptr, 0);
    return png;
}

std::string temporarySiblingPath(const std::string& path) {
    fs::path p(path);
    fs::path dir = p.parent_path();
    if (p.filename().empty()) throw Error(path + ": output path names no file", ExitCode::Output);
    std::string name = "." + p.filename().string() + ".tmp-" + std::to_string(getpid());
    return (dir / name).string();
}

std::string createTemporary(const std::string& path) {
    const std::string tmp = temporarySiblingPath(path);
    const fs::path dir = fs::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
        throw Error(path + ": output directory '" + dir.string() + "' does not exist", ExitCode::Output);
    std::lock_guard<std::mutex> lock(gTempMutex);
    // O_EXCL | O_NOFOLLOW: never through a symlink or over a file of someone else; a stale temporary
    // of a process that had this pid (or anything planted under its name) is removed once, not followed.
    int fd = -1;
    for (int attempt = 0; attempt < 2 && fd < 0; ++attempt) {
        fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (fd < 0 && errno == EEXIST && attempt == 0 && ::unlink(tmp.c_str()) != 0) break;
    }
    if (fd < 0) throw Error(path + ": cannot write output file: " + std::strerror(errno), ExitCode::Output);
    ::close(fd);
    gTemps.insert(tmp);
    return tmp;
}

int openTemporaryForWrite(const std::string& tmpPath, const std::string& path) {
    const int fd = ::open(tmpPath.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) throw Error(path + ": cannot write output file: " + std::strerror(errno), ExitCode::Output);
    return fd;
}

void commitTemporary(const std::string& tmpPath, const std::string& path) {
    std::lock_guard<std::mutex> lock(gTempMutex);
    gTemps.erase(tmpPath);
    if (std::rename(tmpPath.c_str(), path.c_str()) != 0) {
        int err = errno;
        std::remove(tmpPath.c_str());
        throw Error(path + ": cannot write output file: " + std::strerror(err), ExitCode::Output);
    }
}

void discardTemporary(const std::string& tmpPath) {
    std::lock_guard<std::mutex> lock(gTempMutex);
    gTemps.erase(tmpPath);
    std::remove(tmpPath.c_str());
}

void removeTemporariesForExit() {
    gTempMutex.lock();  // never unlocked: the process is about to exit
    for (const std::string& t : gTemps) ::unlink(t.c_str());
    gTemps.clear();
}

std::string writePng8Uncommitted(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
    checkImage(path, width, height, rgb.size());
    const std::string png = encodePng8(path, width, height, rgb);
    return writeTemporary(path, [&](const std::string& tmp) {
        const int fd = openTemporaryForWrite(tmp, path);
        bool ok = writeAll(fd, png.data(), png.size());
        int err = errno;
        if (::close(fd) != 0 && ok) {
            ok = false;
            err = errno;
        }
        if (!ok) throw Error(path + ": cannot write PNG: " + std::strerror(err), ExitCode::Output);
    });
}

void writePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
    commitTemporary(writePng8Uncommitted(path, width, height, rgb), path);
}

void writePngClamped(const std::string& path, const ImageRGB& img, bool truncate) {
    checkImage(path, img.width, img.height, img.pixels.size());
    std::vector<unsigned char> rgb(img.pixels.size());
    for (size_t i = 0; i < rgb.size(); ++i) {
        float v = img.pixels[i];
        v = v > 0.0f ? std::min(v, 255.0f) : 0.0f;  // NaN -> 0
        rgb[i] = static_cast<unsigned char>(truncate ? std::floor(v) : std::lround(v));
    }
    writePng8(path, img.width, img.height, rgb);
}

namespace {

// OpenEXR output to a file descriptor (the temporary, opened with O_NOFOLLOW).
class FdOStream : public Imf::OStream {
public:
    FdOStream(int fd, const std::string& path) : Imf::OStream(path.c_str()), fd_(fd), path_(path) {}
    void write(const char c[], int n) override {
        if (n < 0 || !writeAll(fd_, c, size_t(n))) fail();
        pos_ += uint64_t(n);
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override {
        if (::lseek(fd_, off_t(pos), SEEK_SET) < 0) fail();
        pos_ = pos;
    }

private:
    [[noreturn]] void fail() { throw Error(path_ + ": cannot write EXR: " + std::strerror(errno), ExitCode::Output); }
    int fd_;
    std::string path_;
    uint64_t pos_ = 0;
};

void writeExrTo(const std::string& tmp, const std::string& path, const ImageRGB& img, const ExrWriteOptions& opts) {
    Imf::Header hdr(img.width, img.height);
    hdr.compression() = Imf::ZIP_COMPRESSION;
    // zlib level 1 instead of OpenEXR's default 4: float radiance hardly compresses at any
    // level (Audi TT 1500x833: +1.5% bytes), and compression is the EXR write's whole cost.
    hdr.zipCompressionLevel() = 1;
    const Imf::PixelType type = opts.half ? Imf::HALF : Imf::FLOAT;
    const char* names[3] = {"R", "G", "B"};
    for (const char* n : names) hdr.channels().insert(n, Imf::Channel(type));
    for (const auto& kv : opts.attributes) hdr.insert(kv.first, Imf::StringAttribute(kv.second));

    std::vector<Imath::half> halves;
    const char* base = reinterpret_cast<const char*>(img.pixels.data());
    size_t elem = sizeof(float);
    if (opts.half) {
        halves.assign(img.pixels.begin(), img.pixels.end());
        base = reinterpret_cast<const char*>(halves.data());
        elem = sizeof(Imath::half);
    }
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c)
        fb.insert(names[c], Imf::Slice(type, const_cast<char*>(base + c * elem), 3 * elem, 3 * elem * size_t(img.width)));
    const int fd = openTemporaryForWrite(tmp, path);
    try {
        FdOStream os(fd, path);
        {
            Imf::OutputFile out(os, hdr);
            out.setFrameBuffer(fb);
            out.writePixels(img.height);
        }
    } catch (...) {
        ::close(fd);
        throw;
    }
    if (::close(fd) != 0) throw Error(path + ": cannot write EXR: " + std::strerror(errno), ExitCode::Output);
}

}  // namespace

std::string writeExrUncommitted(const std::string& path, const ImageRGB& img, const ExrWriteOptions& opts) {
    if (img.width <= 0 || img.height <= 0 || img.pixels.size() != size_t(img.width) * size_t(img.height) * 3)
        throw Error(path + ": cannot write an image of " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                        " with " + std::to_string(img.pixels.size()) + " values",
                    ExitCode::Output);
    initExrThreads();  // OpenEXR compresses the ZIP chunks on its thread pool
    return writeTemporary(path, [&](const std::string& tmp) {
        try {
            writeExrTo(tmp, path, img, opts);
        } catch (const Error&) {
            throw;
        } catch (const std::exception& e) {
            std::string what = e.what();
            std::replace(what.begin(), what.end(), '\n', ' ');
            throw Error(path + ": cannot write EXR: " + what, ExitCode::Output);
        }
    });
}

void writeExr(const std::string& path, const ImageRGB& img, const ExrWriteOptions& opts) {
    commitTemporary(writeExrUncommitted(path, img, opts), path);
}

}  // namespace clrt
