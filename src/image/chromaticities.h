// Colour primaries of image files: the conversion of an EXR's linear RGB, given in the primaries and
// white point of its `chromaticities` header attribute, to clrt's working space (linear Rec.709 /
// sRGB primaries, D65 white). The standard construction: RGB -> XYZ from the primaries and white
// point, then, when the white points differ, a Bradford chromatic adaptation of XYZ to D65, then XYZ ->
// Rec.709. Used by the EXR reader (image_io.cpp); no OpenEXR types here.
#pragma once

namespace clrt {

// CIE 1931 xy chromaticities of the three primaries and the white point.
struct Primaries {
    double red[2], green[2], blue[2], white[2];
};

// ITU-R BT.709 (sRGB) primaries with the D65 white point: clrt's working space, and OpenEXR's
// default when a file carries no chromaticities.
constexpr Primaries kRec709Primaries = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}, {0.3127, 0.3290}};

// True when every coordinate of a and b differs by at most 1e-5 (files store them as 32-bit floats).
bool samePrimaries(const Primaries& a, const Primaries& b);

// m (row-major 3x3) maps linear RGB in `from` to linear RGB in `to`: rgbTo = m · rgbFrom. Bradford
// adaptation between the white points when they differ (identity adaptation when they agree).
// Returns false for degenerate primaries (collinear, or a y of 0), leaving m unchanged.
bool rgbToRgbMatrix(const Primaries& from, const Primaries& to, double m[3][3]);

// Converts interleaved RGB `pixels` (count texels) in place from `from` to Rec.709/D65. Does nothing
// (the values stay bit for bit) when `from` is Rec.709/D65. Returns false for degenerate primaries.
bool convertToRec709(float* pixels, long long count, const Primaries& from);

}  // namespace clrt
