// Colour-primaries conversion (chromaticities.h): RGB -> XYZ matrices from xy primaries and white
// point, Bradford chromatic adaptation between white points, and the in-place conversion of an
// image's texels to linear Rec.709 / D65. Reads no files.
#include "image/chromaticities.h"

#include <cmath>

namespace clrt {
namespace {

using Mat3 = double[3][3];

void multiply(const Mat3 a, const Mat3 b, Mat3 out) {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[i][j] = r[i][j];
}

void apply(const Mat3 m, const double v[3], double out[3]) {
    for (int i = 0; i < 3; ++i) out[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
}

// Inverse by cofactors; false when singular.
bool invert(const Mat3 m, Mat3 out) {
    double c[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            c[j][i] = m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1];  // adjugate (transposed cofactors)
        }
    double det = m[0][0] * c[0][0] + m[0][1] * c[1][0] + m[0][2] * c[2][0];
    if (!(std::fabs(det) > 1e-12) || !std::isfinite(det)) return false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[i][j] = c[i][j] / det;
    return true;
}

// XYZ of chromaticity xy at luminance Y = 1 (y may be negative: ACES AP0's blue is imaginary).
bool xyToXyz(const double xy[2], double out[3]) {
    if (!(std::fabs(xy[1]) > 1e-9) || !std::isfinite(xy[0]) || !std::isfinite(xy[1])) return false;
    out[0] = xy[0] / xy[1];
    out[1] = 1.0;
    out[2] = (1.0 - xy[0] - xy[1]) / xy[1];
    return true;
}

// RGB -> XYZ: the primaries' XYZ as columns, each scaled so that RGB (1,1,1) is the white point at Y = 1.
bool rgbToXyz(const Primaries& p, Mat3 out) {
    double r[3], g[3], b[3], w[3];
    if (!xyToXyz(p.red, r) || !xyToXyz(p.green, g) || !xyToXyz(p.blue, b) || !xyToXyz(p.white, w)) return false;
    Mat3 cols = {{r[0], g[0], b[0]}, {r[1], g[1], b[1]}, {r[2], g[2], b[2]}};
    Mat3 inv;
    if (!invert(cols, inv)) return false;
    double s[3];
    apply(inv, w, s);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[i][j] = cols[i][j] * s[j];
    return true;
}

// Bradford adaptation of XYZ from white point `from` to white point `to` (Lam 1985, as in ICC v4).
bool bradford(const double from[2], const double to[2], Mat3 out) {
    static const Mat3 kBradford = {{0.8951, 0.2664, -0.1614}, {-0.7502, 1.7135, 0.0367}, {0.0389, -0.0685, 1.0296}};
    double wf[3], wt[3], cf[3], ct[3];
    if (!xyToXyz(from, wf) || !xyToXyz(to, wt)) return false;
    apply(kBradford, wf, cf);
    apply(kBradford, wt, ct);
    Mat3 inv;
    if (!invert(kBradford, inv)) return false;
    Mat3 scale = {{ct[0] / cf[0], 0, 0}, {0, ct[1] / cf[1], 0}, {0, 0, ct[2] / cf[2]}};
    multiply(scale, kBradford, out);
    multiply(inv, out, out);
    return true;
}

bool sameXy(const double a[2], const double b[2]) {
    return std::fabs(a[0] - b[0]) <= 1e-5 && std::fabs(a[1] - b[1]) <= 1e-5;
}

}  // namespace

bool samePrimaries(const Primaries& a, const Primaries& b) {
    return sameXy(a.red, b.red) && sameXy(a.green, b.green) && sameXy(a.blue, b.blue) && sameXy(a.white, b.white);
}

bool rgbToRgbMatrix(const Primaries& from, const Primaries& to, double m[3][3]) {
    Mat3 toXyz, fromXyz, toRgb, adapt = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (!rgbToXyz(from, toXyz) || !rgbToXyz(to, fromXyz) || !invert(fromXyz, toRgb)) return false;
    if (!sameXy(from.white, to.white) && !bradford(from.white, to.white, adapt)) return false;
    Mat3 r;
    multiply(adapt, toXyz, r);
    multiply(toRgb, r, r);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m[i][j] = r[i][j];
    return true;
}

bool convertToRec709(float* pixels, long long count, const Primaries& from) {
    if (samePrimaries(from, kRec709Primaries)) return true;
    double m[3][3];
    if (!rgbToRgbMatrix(from, kRec709Primaries, m)) return false;
    for (long long i = 0; i < count; ++i) {
        float* p = pixels + 3 * i;
        const double v[3] = {p[0], p[1], p[2]};
        for (int c = 0; c < 3; ++c) p[c] = float(m[c][0] * v[0] + m[c][1] * v[1] + m[c][2] * v[2]);
    }
    return true;
}

}  // namespace clrt
