// Composition of object transformation strings ("t1 s2 r1 c1") from the named Translation, Scaling,
// Rotation and Composite elements of <Transformations>; see transforms.h for the order convention.
#include "scene/transforms.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "util/error.h"

namespace clrt {

Mat4 makeRotation(double angleDeg, double ax, double ay, double az) {
    Mat4 r;
    double len = std::sqrt(ax * ax + ay * ay + az * az);
    if (len == 0) return r;
    double x = ax / len, y = ay / len, z = az / len;
    double a = angleDeg * M_PI / 180.0, c = std::cos(a), s = std::sin(a), t = 1 - c;
    r.m[0][0] = t * x * x + c;     r.m[0][1] = t * x * y - s * z; r.m[0][2] = t * x * z + s * y;
    r.m[1][0] = t * x * y + s * z; r.m[1][1] = t * y * y + c;     r.m[1][2] = t * y * z - s * x;
    r.m[2][0] = t * x * z - s * y; r.m[2][1] = t * y * z + s * x; r.m[2][2] = t * z * z + c;
    return r;
}

Mat4 makeComposite(const double v[16]) {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = v[i * 4 + j];
    return r;
}

Mat4 composeTransforms(const std::string& refs, const TransformTable& table, const std::string& where) {
    Mat4 m = Mat4::identity();
    std::istringstream in(refs);
    std::string tok;
    while (in >> tok) {
        char kind = char(std::tolower(static_cast<unsigned char>(tok[0])));
        const std::map<int, Mat4>* map = nullptr;
        const char* what = "";
        switch (kind) {
            case 't': map = &table.translations; what = "Translation"; break;
            case 's': map = &table.scalings; what = "Scaling"; break;
            case 'r': map = &table.rotations; what = "Rotation"; break;
            case 'c': map = &table.composites; what = "Composite"; break;
            default:
                throw Error(where + ": bad transformation reference '" + tok +
                            "' (expected t<id>, s<id>, r<id> or c<id>)");
        }
        std::string digits = tok.substr(1);
        char* end = nullptr;
        errno = 0;
        long id = digits.empty() ? 0 : std::strtol(digits.c_str(), &end, 10);
        if (digits.empty() || *end != '\0' || !std::isdigit(static_cast<unsigned char>(digits[0])))
            throw Error(where + ": bad transformation reference '" + tok +
                        "' (expected t<id>, s<id>, r<id> or c<id>)");
        if (errno == ERANGE || id > std::numeric_limits<int>::max())  // would wrap onto another id
            throw Error(where + ": transformation '" + tok + "': id out of range");
        auto it = map->find(int(id));
        if (it == map->end())
            throw Error(where + ": transformation '" + tok + "' references undefined " + what + " " +
                        std::to_string(id));
        m = it->second * m;  // applied after everything before it
    }
    return m;
}

bool isSimilarity(const Mat4& m, double relTol) {
    double g[3][3], tr = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            g[i][j] = m.m[0][i] * m.m[0][j] + m.m[1][i] * m.m[1][j] + m.m[2][i] * m.m[2][j];
            if (i == j) tr += g[i][j];
        }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (std::fabs(g[i][j] - (i == j ? tr / 3 : 0.0)) > relTol * tr) return false;
    return tr > 0;
}

double linearDeterminant(const Mat4& m) {
    const auto& a = m.m;
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

}  // namespace clrt
