// PLY reader (see ply_reader.h). The file is memory-mapped (read into memory where it cannot be); the
// header is parsed into a list of elements and properties, then every element is walked in order with
// one value reader per format (ASCII tokens or little/big-endian binary). The common binary layouts
// (float vertex properties; triangles as `list uchar int`) take a direct path that reads each value
// straight into the mesh arrays; it hands any element or face it does not expect to the general
// reader, so messages and results are the same either way. Only the vertex and face elements are kept; everything
// else (edges, materials, extra properties, list properties on vertices) is read and dropped.
// Counts are checked against the bytes left before anything is allocated, so a header that lies
// about its counts gives an error instead of a huge allocation or a read past the end. Every value is
// read as a double and range-checked before it becomes a float or an int: a vertex coordinate, normal
// or texture coordinate that is NaN, infinite or beyond float range (1e39) is an error naming the
// vertex and its line (ASCII) or byte offset (binary), and so is a face index outside [0, INT_MAX].
#include "scene/ply_reader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/error.h"

namespace clrt {
namespace {

enum class Format { Ascii, BinaryLE, BinaryBE };
enum class Type { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct Property {
    std::string name;
    bool isList = false;
    Type countType = Type::UInt8;  // lists only
    Type valueType = Type::Float32;
};

struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> props;
};

bool parseType(const std::string& s, Type& t) {
    static const struct { const char* name; Type type; } kTypes[] = {
        {"char", Type::Int8},     {"int8", Type::Int8},       {"uchar", Type::UInt8},    {"uint8", Type::UInt8},
        {"short", Type::Int16},   {"int16", Type::Int16},     {"ushort", Type::UInt16},  {"uint16", Type::UInt16},
        {"int", Type::Int32},     {"int32", Type::Int32},     {"uint", Type::UInt32},    {"uint32", Type::UInt32},
        {"float", Type::Float32}, {"float32", Type::Float32}, {"double", Type::Float64}, {"float64", Type::Float64},
    };
    for (const auto& e : kTypes)
        if (s == e.name) { t = e.type; return true; }
    return false;
}

size_t typeSize(Type t) {
    switch (t) {
        case Type::Int8: case Type::UInt8: return 1;
        case Type::Int16: case Type::UInt16: return 2;
        case Type::Int32: case Type::UInt32: case Type::Float32: return 4;
        case Type::Float64: return 8;
    }
    return 1;
}

bool isIntegral(Type t) { return t != Type::Float32 && t != Type::Float64; }

// A double as a message shows it: integers below 1e17 exactly, anything else with 9 significant
// digits. (No cast to an integer type: the value may be far beyond any integer's range.)
std::string numberText(double v) {
    char buf[48];
    if (std::fabs(v) < 1e17 && v == std::floor(v)) std::snprintf(buf, sizeof buf, "%.0f", v);
    else std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

// v as a finite float, or false if v is NaN, infinite or beyond float range.
bool finiteFloat(double v, float& out) {
    if (!(std::fabs(v) <= double(std::numeric_limits<float>::max()))) return false;
    out = float(v);
    return true;
}

bool hostIsLittleEndian() {
    uint16_t one = 1;
    unsigned char b;
    std::memcpy(&b, &one, 1);
    return b == 1;
}

// Sequential reader over the data section. Every value comes back as a double: all PLY scalar types
// (at most 32-bit integers, float, double) are exactly representable.
class DataReader {
public:
    DataReader(const std::string& path, std::string_view data, size_t pos, Format fmt)
        : path_(path), data_(data), pos_(pos), fmt_(fmt),
          swap_((fmt == Format::BinaryLE) != hostIsLittleEndian()) {}

    size_t remaining() const { return data_.size() - pos_; }
    Format format() const { return fmt_; }
    // Binary data in the host's byte order (the direct paths of readVertices and readFaces).
    bool nativeBinary() const { return fmt_ != Format::Ascii && !swap_; }
    const char* cursor() const { return data_.data() + pos_; }
    void advance(size_t n) { pos_ += n; }

    double read(Type t, const char* what) {
        return fmt_ == Format::Ascii ? readAscii(t, what) : readBinary(t, what);
    }

    // Where we are, for messages: "line N" in ASCII, "byte N" in binary.
    std::string where() const {
        if (fmt_ != Format::Ascii) return "byte " + std::to_string(pos_);
        return "line " + std::to_string(line_);
    }

    void setStartLine(size_t line) { line_ = line; }

    // A list property's count; a negative one (a signed count type) is an error, naming the face
    // when `face` is given.
    double listCount(Type t, const char* what, const uint64_t* face = nullptr) {
        double n = read(t, what);
        if (n < 0)
            throw Error(path_ + ": " + where() + ": negative list count" +
                        (face ? " in face " + std::to_string(*face) : std::string()));
        return n;
    }

    // Reads n values of type t and drops them.
    void skip(Type t, double n, const char* what) {
        for (double k = 0; k < n; ++k) read(t, what);
    }

private:
    [[noreturn]] void truncated(const char* what) const {
        throw Error(path_ + ": file ends early while reading " + what +
                    " (the header lies about counts, or the file is truncated)");
    }

    double readBinary(Type t, const char* what) {
        size_t n = typeSize(t);
        if (remaining() < n) truncated(what);
        unsigned char b[8];
        std::memcpy(b, data_.data() + pos_, n);
        pos_ += n;
        if (swap_)
            for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
        switch (t) {
            case Type::Int8: { int8_t v; std::memcpy(&v, b, 1); return v; }
            case Type::UInt8: return b[0];
            case Type::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
            case Type::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
            case Type::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
            case Type::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
            case Type::Float32: { float v; std::memcpy(&v, b, 4); return v; }
            case Type::Float64: { double v; std::memcpy(&v, b, 8); return v; }
        }
        return 0;
    }

    // Skips whitespace (CR and LF included), counting lines.
    void skipSpace() {
        while (pos_ < data_.size()) {
            char c = data_[pos_];
            if (c == '\n') ++line_;
            else if (c != ' ' && c != '\t' && c != '\r' && c != '\f' && c != '\v') break;
            ++pos_;
        }
    }

    double readAscii(Type t, const char* what) {
        skipSpace();
        size_t start = pos_;
        while (pos_ < data_.size() && !std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
        if (start == pos_) truncated(what);
        std::string tok(data_.substr(start, pos_ - start));
        char* end = nullptr;
        errno = 0;
        double v = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0')
            throw Error(path_ + ": line " + std::to_string(line_) + ": '" + tok + "' is not a number (" + what + ")");
        if (isIntegral(t) && (!std::isfinite(v) || v != std::floor(v)))
            throw Error(path_ + ": line " + std::to_string(line_) + ": '" + tok + "' is not an integer (" + what + ")");
        // Rounded to float as a binary file would store it; a value beyond float range stays as it
        // is (converting it is undefined) and is refused where it is used (finiteFloat).
        if (t == Type::Float32 && std::fabs(v) <= double(std::numeric_limits<float>::max())) v = static_cast<float>(v);
        return v;
    }

    const std::string& path_;
    std::string_view data_;
    size_t pos_;
    Format fmt_;
    bool swap_;
    size_t line_ = 1;
};

struct Header {
    Format format = Format::Ascii;
    std::vector<Element> elements;
    size_t dataStart = 0;  // byte offset of the first data byte
    size_t dataLine = 1;   // line number of the first data line (ASCII messages)
};

// The header's lines after the magic word, one at a time, into a Header.
struct HeaderParser {
    const std::string& path;
    Header h;
    size_t lineNo = 0;
    bool sawFormat = false;

    explicit HeaderParser(const std::string& p) : path(p) {}

    Error bad(const std::string& why) const {
        return Error(path + ": bad PLY header, line " + std::to_string(lineNo) + ": " + why);
    }

    // One line; false at end_header.
    bool keywordLine(const std::string& line) {
        std::istringstream ls(line);
        std::string kw;
        if (!(ls >> kw)) return true;  // blank line
        if (kw == "comment" || kw == "obj_info") return true;
        if (kw == "end_header") return false;
        if (kw == "format") formatLine(ls);
        else if (kw == "element") elementLine(ls);
        else if (kw == "property") propertyLine(ls);
        else throw bad("unknown keyword '" + kw + "'");
        return true;
    }

    void formatLine(std::istringstream& ls) {
        std::string f, version;
        if (!(ls >> f >> version)) throw bad("expected 'format <type> <version>'");
        if (f == "ascii") h.format = Format::Ascii;
        else if (f == "binary_little_endian") h.format = Format::BinaryLE;
        else if (f == "binary_big_endian") h.format = Format::BinaryBE;
        else throw Error(path + ": unsupported PLY format '" + f + "'");
        sawFormat = true;
    }

    void elementLine(std::istringstream& ls) {
        Element e;
        std::string count;
        if (!(ls >> e.name >> count)) throw bad("expected 'element <name> <count>'");
        if (count.empty() || count.find_first_not_of("0123456789") != std::string::npos)
            throw bad("element count '" + count + "' is not a non-negative integer");
        errno = 0;
        unsigned long long c = std::strtoull(count.c_str(), nullptr, 10);
        if (errno == ERANGE) throw bad("element count '" + count + "' is too large");
        e.count = c;
        h.elements.push_back(e);
    }

    void propertyLine(std::istringstream& ls) {
        if (h.elements.empty()) throw bad("property before any element");
        Property p;
        std::string t;
        if (!(ls >> t)) throw bad("expected a property type");
        if (t == "list") {
            std::string ct, vt;
            p.isList = true;
            if (!(ls >> ct >> vt >> p.name)) throw bad("expected 'property list <count type> <type> <name>'");
            if (!parseType(ct, p.countType)) throw bad("unknown type '" + ct + "'");
            if (!isIntegral(p.countType)) throw bad("list count type '" + ct + "' is not an integer type");
            if (!parseType(vt, p.valueType)) throw bad("unknown type '" + vt + "'");
        } else {
            if (!parseType(t, p.valueType)) throw bad("unknown type '" + t + "'");
            if (!(ls >> p.name)) throw bad("expected a property name");
        }
        h.elements.back().props.push_back(p);
    }
};

Header parseHeader(const std::string& path, std::string_view bytes) {
    if (bytes.substr(0, 3) != "ply") throw Error(path + ": not a PLY file (it does not start with 'ply')");
    HeaderParser hp(path);
    bool sawEnd = false;
    size_t pos = 0;
    while (pos < bytes.size()) {
        size_t nl = bytes.find('\n', pos);
        size_t end = nl == std::string::npos ? bytes.size() : nl;
        std::string line(bytes.substr(pos, end - pos));
        pos = nl == std::string::npos ? bytes.size() : nl + 1;
        ++hp.lineNo;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (hp.lineNo == 1) {
            // Tolerate trailing blanks after the magic word, nothing else.
            if (line.compare(0, 3, "ply") != 0 || line.find_first_not_of(" \t", 3) != std::string::npos)
                throw Error(path + ": not a PLY file (it does not start with 'ply')");
            continue;
        }
        if (!hp.keywordLine(line)) { sawEnd = true; break; }
    }
    if (!sawEnd) throw Error(path + ": bad PLY header: no 'end_header' line");
    if (!hp.sawFormat) throw Error(path + ": bad PLY header: no 'format' line");
    hp.h.dataStart = pos;
    hp.h.dataLine = hp.lineNo + 1;
    return hp.h;
}

int findProp(const Element& e, const char* name) {
    for (size_t i = 0; i < e.props.size(); ++i)
        if (!e.props[i].isList && e.props[i].name == name) return int(i);
    return -1;
}

// Fewest bytes (binary) or tokens (ASCII: at least 1 byte each) one element of `e` can take.
size_t minElementSize(const Element& e, Format fmt) {
    size_t n = 0;
    for (const Property& p : e.props)
        n += fmt == Format::Ascii ? 1 : typeSize(p.isList ? p.countType : p.valueType);
    return n;
}

// The whole file, memory-mapped read-only (no copy: pages come from the page cache as they are read),
// or read into memory where mapping fails. Directories, FIFOs and devices (/dev/zero) are refused.
class FileBytes {
public:
    explicit FileBytes(const std::string& path) {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path, ec))
            throw Error(path + (std::filesystem::exists(path, ec) ? ": cannot open PLY file: not a regular file"
                                                                  : ": cannot open PLY file: no such file"));
        const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
        struct stat st {};
        if (fd >= 0 && fstat(fd, &st) == 0 && st.st_size > 0) {
            void* p = mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
            if (p != MAP_FAILED) {
                map_ = p;
                size_ = size_t(st.st_size);
                madvise(p, size_, MADV_SEQUENTIAL);
            }
        }
        if (fd >= 0) close(fd);
        if (map_) return;
        std::ifstream in(path, std::ios::binary);
        if (!in) throw Error(path + ": cannot open PLY file");
        copy_.assign((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (in.bad()) throw Error(path + ": cannot read PLY file");
    }
    ~FileBytes() {
        if (map_) munmap(map_, size_);
    }
    FileBytes(const FileBytes&) = delete;
    FileBytes& operator=(const FileBytes&) = delete;
    std::string_view view() const { return map_ ? std::string_view(static_cast<const char*>(map_), size_) : copy_; }

private:
    void* map_ = nullptr;
    size_t size_ = 0;
    std::string copy_;
};

// Where x y z [nx ny nz] [u v] are among a vertex element's properties: want[k] is the property of
// out value k, -1 when the file has none.
struct VertexLayout {
    int want[8];
    bool hasN, hasUv;
};

VertexLayout vertexLayout(const std::string& path, const Element& e) {
    int ix = findProp(e, "x"), iy = findProp(e, "y"), iz = findProp(e, "z");
    if (ix < 0 || iy < 0 || iz < 0) throw Error(path + ": vertex element lacks an x, y or z property");
    int inx = findProp(e, "nx"), iny = findProp(e, "ny"), inz = findProp(e, "nz");
    bool hasN = inx >= 0 && iny >= 0 && inz >= 0;
    int iu = -1, iv = -1;
    static const char* kUv[][2] = {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
    for (const auto& uv : kUv) {
        iu = findProp(e, uv[0]);
        iv = findProp(e, uv[1]);
        if (iu >= 0 && iv >= 0) break;
    }
    bool hasUv = iu >= 0 && iv >= 0;
    return VertexLayout{{ix, iy, iz, hasN ? inx : -1, hasN ? iny : -1, hasN ? inz : -1, hasUv ? iu : -1,
                         hasUv ? iv : -1},
                        hasN, hasUv};
}

// The direct path of readVertices: binary in the host's byte order with only float properties (the
// usual layout): each vertex's floats copied straight into the arrays. Returns the vertices it read,
// stopping before the first with a non-finite wanted value (the general loop then reports it).
uint64_t readFloatVertices(const Element& e, const VertexLayout& layout, DataReader& rd, MeshData& mesh) {
    if (!rd.nativeBinary()) return 0;
    for (const Property& p : e.props)
        if (p.isList || p.valueType != Type::Float32) return 0;
    const size_t stride = 4 * e.props.size();
    uint64_t i = 0;
    for (const char* v = rd.cursor(); i < e.count; ++i, v += stride) {
        float out[8] = {};
        bool finite = true;
        for (int k = 0; k < 8; ++k)
            if (layout.want[k] >= 0) {
                std::memcpy(&out[k], v + 4 * layout.want[k], 4);
                finite = finite && std::isfinite(out[k]);
            }
        if (!finite) break;
        mesh.positions[i] = Vec3(out[0], out[1], out[2]);
        if (layout.hasN) mesh.normals[i] = Vec3(out[3], out[4], out[5]);
        if (layout.hasUv) mesh.uvs[i] = Vec2{out[6], out[7]};
    }
    rd.advance(size_t(i) * stride);
    return i;
}

// The vertex element: positions, and normals and texture coordinates when it has them all.
void readVertices(const std::string& path, const Element& e, DataReader& rd, MeshData& mesh) {
    if (e.count > uint64_t(std::numeric_limits<int>::max()))
        throw Error(path + ": too many vertices (" + std::to_string(e.count) + ")");
    const VertexLayout layout = vertexLayout(path, e);
    mesh.positions.resize(e.count);
    if (layout.hasN) mesh.normals.resize(e.count);
    if (layout.hasUv) mesh.uvs.resize(e.count);
    std::vector<double> vals(e.props.size());
    for (uint64_t i = readFloatVertices(e, layout, rd, mesh); i < e.count; ++i) {
        for (size_t p = 0; p < e.props.size(); ++p) {
            const Property& pr = e.props[p];
            if (pr.isList) rd.skip(pr.valueType, rd.listCount(pr.countType, "a vertex list count"), "a vertex list");
            else vals[p] = rd.read(pr.valueType, "vertex data");
        }
        // x y z [nx ny nz] [u v] into out[0..7], each a finite float or an error.
        float out[8] = {};
        for (int k = 0; k < 8; ++k) {
            const int w = layout.want[k];
            if (w >= 0 && !finiteFloat(vals[size_t(w)], out[k]))
                throw Error(path + ": " + rd.where() + ": vertex " + std::to_string(i) + " has " +
                            e.props[size_t(w)].name + " = " + numberText(vals[size_t(w)]) +
                            ", not a finite 32-bit float");
        }
        mesh.positions[i] = Vec3(out[0], out[1], out[2]);
        if (layout.hasN) mesh.normals[i] = Vec3(out[3], out[4], out[5]);
        if (layout.hasUv) mesh.uvs[i] = Vec2{out[6], out[7]};
    }
}

// The face element's vertex index list property (the last one so named).
size_t faceListProperty(const std::string& path, const Element& e) {
    int list = -1;
    for (size_t p = 0; p < e.props.size(); ++p)
        if (e.props[p].isList && (e.props[p].name == "vertex_indices" || e.props[p].name == "vertex_index"))
            list = int(p);
    if (list < 0) throw Error(path + ": face element has no 'vertex_indices' list property");
    if (!isIntegral(e.props[size_t(list)].valueType))
        throw Error(path + ": face vertex indices have a floating-point type");
    return size_t(list);
}

// The n vertex indices of face f, fanned into triangles appended to `indices`.
void readPolygon(const std::string& path, const Property& pr, double n, uint64_t f, DataReader& rd,
                 std::vector<int>& poly, std::vector<int>& indices) {
    poly.clear();
    for (double k = 0; k < n; ++k) {
        double idx = rd.read(pr.valueType, "face indices");
        if (idx < 0 || idx > double(std::numeric_limits<int>::max()))
            throw Error(path + ": " + rd.where() + ": face " + std::to_string(f) + " has vertex index " +
                        numberText(idx) + ", out of range");
        poly.push_back(int(idx));
    }
    for (size_t k = 1; k + 1 < poly.size(); ++k) {
        indices.push_back(poly[0]);
        indices.push_back(poly[k]);
        indices.push_back(poly[k + 1]);
    }
}

// The direct path of readFaces: binary in the host's byte order, the face element nothing but a
// `list uchar|char int|uint` (the usual layout): triangles copied straight into mesh.indices. Returns
// the faces it read, stopping before the first that is not a triangle of indices in [0, INT_MAX] (the
// general loop goes on from there).
uint64_t readTriangleFaces(const Element& e, DataReader& rd, MeshData& mesh) {
    if (!rd.nativeBinary() || e.props.size() != 1) return 0;
    const Property& p = e.props[0];
    if ((p.countType != Type::UInt8 && p.countType != Type::Int8) ||
        (p.valueType != Type::Int32 && p.valueType != Type::UInt32))
        return 0;
    const size_t available = rd.remaining() / 13;
    const uint64_t most = std::min<uint64_t>(e.count, available);
    mesh.indices.resize(size_t(most) * 3);
    int* out = mesh.indices.data();
    uint64_t f = 0;
    for (const char* c = rd.cursor(); f < most; ++f, c += 13) {
        int32_t idx[3];
        std::memcpy(idx, c + 1, 12);
        if (c[0] != 3 || (idx[0] | idx[1] | idx[2]) < 0) break;  // (uint: above INT_MAX, negative here)
        std::memcpy(out + 3 * f, idx, 12);
    }
    mesh.indices.resize(size_t(f) * 3);
    rd.advance(size_t(f) * 13);
    return f;
}

// The face element: its polygons as triangles; other properties read and dropped.
void readFaces(const std::string& path, const Element& e, DataReader& rd, MeshData& mesh) {
    const size_t list = faceListProperty(path, e);
    mesh.indices.reserve(size_t(e.count) * 3);  // bounded by the size check in readPly
    std::vector<int> poly;
    for (uint64_t f = readTriangleFaces(e, rd, mesh); f < e.count; ++f) {
        for (size_t p = 0; p < e.props.size(); ++p) {
            const Property& pr = e.props[p];
            if (!pr.isList) { rd.read(pr.valueType, "face data"); continue; }
            double n = rd.listCount(pr.countType, "a face list count", &f);
            if (p != list) rd.skip(pr.valueType, n, "a face list");
            else readPolygon(path, pr, n, f, rd, poly, mesh.indices);
        }
    }
}

// Any other element: read (so that the data are checked) and dropped.
void skipElement(const Element& e, DataReader& rd) {
    for (uint64_t i = 0; i < e.count; ++i)
        for (const Property& pr : e.props) {
            if (!pr.isList) { rd.read(pr.valueType, e.name.c_str()); continue; }
            rd.skip(pr.valueType, rd.listCount(pr.countType, e.name.c_str()), e.name.c_str());
        }
}

void checkFaceIndices(const std::string& path, const MeshData& mesh) {
    const size_t nv = mesh.positions.size();
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (size_t(mesh.indices[i]) >= nv)
            throw Error(path + ": triangle " + std::to_string(i / 3) + " uses vertex index " +
                        std::to_string(mesh.indices[i]) + " but there are only " + std::to_string(nv) + " vertices");
}

}  // namespace

MeshData readPly(const std::string& path) {
    const FileBytes file(path);
    const std::string_view bytes = file.view();
    Header h = parseHeader(path, bytes);
    DataReader rd(path, bytes, h.dataStart, h.format);
    rd.setStartLine(h.dataLine);

    MeshData mesh;
    bool sawVertex = false, sawFace = false;
    for (const Element& e : h.elements) {
        if (e.props.empty()) continue;  // nothing to read, whatever the count says
        size_t minSize = minElementSize(e, h.format);
        if (e.count > rd.remaining() / minSize)
            throw Error(path + ": header says " + std::to_string(e.count) + " " + e.name +
                        " elements but the file is too short to hold them (the header lies about counts)");
        const bool isVertex = e.name == "vertex", isFace = e.name == "face";
        if ((isVertex && sawVertex) || (isFace && sawFace))
            throw Error(path + ": more than one '" + e.name + "' element");
        if (isVertex) {
            sawVertex = true;
            readVertices(path, e, rd, mesh);
        } else if (isFace) {
            sawFace = true;
            readFaces(path, e, rd, mesh);
        } else {
            skipElement(e, rd);
        }
    }
    if (!sawVertex) throw Error(path + ": PLY file has no vertex element");
    checkFaceIndices(path, mesh);
    return mesh;
}

}  // namespace clrt
