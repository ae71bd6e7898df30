// EXR chromaticities (issue 29): an EXR whose header carries a `chromaticities` attribute is converted
// on load to clrt's working space, linear Rec.709 primaries with a D65 white (image/chromaticities.h).
// Maps are written here through OpenEXR with other primaries and read through readImage (what
// environment maps and image textures load with): Rec.2020 against the published BT.2020 -> BT.709
// matrix (ITU-R BT.2087), ACES AP0 (white ≈ D60: Bradford adaptation) against white staying white and
// the conversion of its primaries' XYZ; a file without the attribute, or with Rec.709's, reads bit for
// bit as written.
#include <catch.hpp>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>

#include "image/chromaticities.h"
#include "image/image.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// A width x 1 FLOAT RGB EXR of `rgb`, with the chromaticities `prim` when given.
void writeRgbExr(const std::string& path, const std::vector<float>& rgb, const Primaries* prim) {
    const int w = int(rgb.size() / 3);
    Imf::Header hdr(w, 1);
    for (const char* c : {"R", "G", "B"}) hdr.channels().insert(c, Imf::Channel(Imf::FLOAT));
    if (prim)
        Imf::addChromaticities(hdr, Imf::Chromaticities(Imath::V2f(float(prim->red[0]), float(prim->red[1])),
                                                        Imath::V2f(float(prim->green[0]), float(prim->green[1])),
                                                        Imath::V2f(float(prim->blue[0]), float(prim->blue[1])),
                                                        Imath::V2f(float(prim->white[0]), float(prim->white[1]))));
    Imf::FrameBuffer fb;
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c)
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, (char*)(rgb.data() + c), 3 * sizeof(float), 0));
    Imf::OutputFile out(path.c_str(), hdr);
    out.setFrameBuffer(fb);
    out.writePixels(1);
}

const Primaries kRec2020 = {{0.708, 0.292}, {0.170, 0.797}, {0.131, 0.046}, {0.3127, 0.3290}};
const Primaries kAcesAp0 = {{0.7347, 0.2653}, {0.0, 1.0}, {0.0001, -0.0770}, {0.32168, 0.33767}};

// ITU-R BT.2087 (and colour-science): linear BT.2020 RGB -> linear BT.709 RGB, both D65.
const double kBt2020To709[3][3] = {{1.66049100, -0.58764114, -0.07284986},
                                   {-0.12455047, 1.13289990, -0.00834942},
                                   {-0.01815076, -0.10057890, 1.11872966}};

// Inside Rec.709's gamut from both Rec.2020 and AP0 (an out-of-gamut texel turns negative and is
// set to 0, as every negative texel is).
const std::vector<float> kTexels = {0.5f, 0.25f, 0.125f, 1.0f, 1.0f, 1.0f, 0.4f, 0.45f, 0.3f, 0.3123457f, 0.3512345f, 0.2834567f};

}  // namespace

TEST_CASE("EXR chromaticities: Rec.2020 texels load as their Rec.709 values", "[image][chromaticities]") {
    TempDir d;
    writeRgbExr(d.file("r2020.exr"), kTexels, &kRec2020);
    ImageRGB img = readImage(d.file("r2020.exr"));
    REQUIRE(img.pixels.size() == kTexels.size());
    for (size_t i = 0; i < kTexels.size(); i += 3)
        for (int c = 0; c < 3; ++c) {
            double want = 0;
            for (int k = 0; k < 3; ++k) want += kBt2020To709[c][k] * double(kTexels[i + size_t(k)]);
            INFO("texel " << i / 3 << " channel " << c);
            CHECK(std::fabs(img.pixels[i + size_t(c)] - want) < 1e-5);
        }
}

TEST_CASE("EXR chromaticities: ACES AP0 (D60 white) adapts to D65 by Bradford", "[image][chromaticities]") {
    TempDir d;
    writeRgbExr(d.file("ap0.exr"), kTexels, &kAcesAp0);
    ImageRGB img = readImage(d.file("ap0.exr"));
    REQUIRE(img.pixels.size() == kTexels.size());
    // White (texel 1) is white after adaptation.
    for (int c = 0; c < 3; ++c) CHECK(std::fabs(img.pixels[3 + size_t(c)] - 1.0f) < 1e-5f);
    // The matrix agrees with the published ACES2065-1 -> linear sRGB matrix (Bradford; colour-science).
    double m[3][3];
    REQUIRE(rgbToRgbMatrix(kAcesAp0, kRec709Primaries, m));
    const double published[3][3] = {{2.52168619, -1.13413099, -0.38755520},
                                    {-0.27647991, 1.37271909, -0.09623918},
                                    {-0.01537802, -0.15297534, 1.16835337}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            INFO("m[" << i << "][" << j << "] = " << m[i][j]);
            CHECK(std::fabs(m[i][j] - published[i][j]) < 1e-6);
        }
    for (size_t i = 0; i < kTexels.size(); i += 3)
        for (int c = 0; c < 3; ++c) {
            double want = m[c][0] * kTexels[i] + m[c][1] * kTexels[i + 1] + m[c][2] * kTexels[i + 2];
            CHECK(std::fabs(img.pixels[i + size_t(c)] - want) < 1e-5);
        }
}

TEST_CASE("EXR chromaticities: none, or Rec.709's, leave the texels bit for bit", "[image][chromaticities]") {
    TempDir d;
    writeRgbExr(d.file("none.exr"), kTexels, nullptr);
    writeRgbExr(d.file("r709.exr"), kTexels, &kRec709Primaries);
    for (const char* name : {"none.exr", "r709.exr"}) {
        INFO(name);
        ImageRGB img = readImage(d.file(name));
        REQUIRE(img.pixels.size() == kTexels.size());
        CHECK(std::memcmp(img.pixels.data(), kTexels.data(), kTexels.size() * sizeof(float)) == 0);
    }
    // Rec.2020 with the same numbers does change them (the test above can fail).
    writeRgbExr(d.file("r2020.exr"), kTexels, &kRec2020);
    CHECK(readImage(d.file("r2020.exr")).pixels != kTexels);
}
