// embree_load — the baseline of scripts/bench_scale: Embree 3's load + build of one binary PLY triangle
// mesh, as an Embree user would do it: the file memory-mapped, its vertices and indices copied once into
// Embree's own geometry buffers, then rtcCommitScene at RTC_BUILD_QUALITY_HIGH on T threads.
// Reads binary_little_endian PLYs whose vertex element has float x, y, z first (other float
// properties after them are skipped) and whose faces are `list uchar int|uint` triangles (what
// scripts/bench_scale writes); anything else is refused.
//
// usage: embree_load FILE.ply [--threads 2] [--quality high|medium]
// prints: "embree_load: N triangles, load S s, build S s, total S s"
#include <embree3/rtcore.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

namespace {

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Header {
    size_t vertices = 0, faces = 0, vertexStride = 0, body = 0;
};

Header parseHeader(const char* data, size_t size) {
    Header h;
    const char* end = static_cast<const char*>(memmem(data, std::min<size_t>(size, 1 << 16), "end_header\n", 11));
    if (!end) throw std::runtime_error("no end_header");
    std::istringstream in(std::string(data, end));
    std::string line, element;
    bool binaryLe = false;
    while (std::getline(in, line)) {
        std::istringstream w(line);
        std::string k, a, b, c, d;
        w >> k >> a >> b >> c >> d;
        if (k == "format") binaryLe = a == "binary_little_endian";
        if (k == "element") {
            element = a;
            (a == "vertex" ? h.vertices : h.faces) = std::stoull(b);
        }
        if (k == "property" && element == "vertex") {
            if (a != "float") throw std::runtime_error("vertex property " + b + " is not a float");
            h.vertexStride += 4;
        }
        if (k == "property" && element == "face" && (a != "list" || b != "uchar" || (c != "int" && c != "uint")))
            throw std::runtime_error("faces must be list uchar int");
    }
    if (!binaryLe || h.vertexStride < 12) throw std::runtime_error("not a binary little-endian PLY with x y z");
    h.body = size_t(end - data) + 11;
    return h;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: embree_load FILE.ply [--threads 2] [--quality high|medium]\n");
        return 1;
    }
    int threads = 2;
    RTCBuildQuality quality = RTC_BUILD_QUALITY_HIGH;
    for (int i = 2; i + 1 < argc; i += 2) {
        if (std::string(argv[i]) == "--threads") threads = std::atoi(argv[i + 1]);
        if (std::string(argv[i]) == "--quality")
            quality = std::string(argv[i + 1]) == "medium" ? RTC_BUILD_QUALITY_MEDIUM : RTC_BUILD_QUALITY_HIGH;
    }
    try {
        auto t0 = std::chrono::steady_clock::now();
        const int fd = open(argv[1], O_RDONLY);
        struct stat st {};
        if (fd < 0 || fstat(fd, &st) != 0) throw std::runtime_error("cannot open the file");
        const size_t size = size_t(st.st_size);
        const char* data = static_cast<const char*>(mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0));
        if (data == MAP_FAILED) throw std::runtime_error("cannot map the file");
        madvise(const_cast<char*>(data), size, MADV_SEQUENTIAL);
        const Header h = parseHeader(data, size);
        if (h.body + h.vertices * h.vertexStride + h.faces * 13 > size) throw std::runtime_error("file too short");

        RTCDevice dev = rtcNewDevice(("threads=" + std::to_string(threads)).c_str());
        RTCScene scene = rtcNewScene(dev);
        rtcSetSceneBuildQuality(scene, quality);
        RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(geom, quality);
        auto* vb = static_cast<float*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, h.vertices));
        auto* ib = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, h.faces));
        const char* p = data + h.body;
        for (size_t v = 0; v < h.vertices; ++v, p += h.vertexStride) std::memcpy(vb + 3 * v, p, 12);
        for (size_t f = 0; f < h.faces; ++f, p += 13) {
            if (static_cast<unsigned char>(*p) != 3) throw std::runtime_error("a face is not a triangle");
            std::memcpy(ib + 3 * f, p + 1, 12);
        }
        munmap(const_cast<char*>(data), size);
        close(fd);
        const double load = since(t0);
        auto t1 = std::chrono::steady_clock::now();
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene);
        const double build = since(t1);
        std::printf("embree_load: %zu triangles, load %.3f s, build %.3f s, total %.3f s\n", h.faces, load, build,
                    since(t0));
        rtcReleaseScene(scene);
        rtcReleaseDevice(dev);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "embree_load: error: %s: %s\n", argv[1], e.what());
        return 2;
    }
}
