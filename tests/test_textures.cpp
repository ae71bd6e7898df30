// The course's 2025 texture additions: Interpolation trilinear (the mip pyramid of
// src/flatten/mip_pyramid.cpp; the level of detail and the trilinear lookup of cl_kernels/textures.cl
// against the host references below; the far checkerboard plane of scenes/mip_checker_plane.xml at
// 1 spp against a 256-spp bilinear render) and NumOctaves (the fractal Perlin sum of textures.cl
// against a host reference; one octave renders as before, byte for byte).
#include <catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "cl/check.h"
#include "flatten/device_scene.h"
#include "flatten/mip_pyramid.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "perlin_reference.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// ---- host references (written out plainly, double precision) ----
struct Rgb {
    double r = 0, g = 0, b = 0;
};

Rgb texelAt(const MipLevel& l, int x, int y) {  // repeat wrap
    x = ((x % l.width) + l.width) % l.width;
    y = ((y % l.height) + l.height) % l.height;
    const dev::float4& c = l.texels[size_t(y) * l.width + x];
    return {c.x, c.y, c.z};
}

Rgb bilinear(const MipLevel& l, double u, double v) {
    double px = u * l.width, py = v * l.height;
    double fx = std::floor(px), fy = std::floor(py), dx = px - fx, dy = py - fy;
    int ix = int(fx), iy = int(fy);
    Rgb a = texelAt(l, ix, iy), b = texelAt(l, ix + 1, iy), c = texelAt(l, ix, iy + 1), d = texelAt(l, ix + 1, iy + 1);
    auto mix = [&](double p, double q, double r, double s) {
        return (1 - dx) * (1 - dy) * p + dx * (1 - dy) * q + (1 - dx) * dy * r + dx * dy * s;
    };
    return {mix(a.r, b.r, c.r, d.r), mix(a.g, b.g, c.g, d.g), mix(a.b, b.b, c.b, d.b)};
}

// λ = log2(footprint in texels of level 0), the footprint's texels across = uv footprint · √(w·h).
double lodLevel(double footprintUv, int w, int h) {
    double across = footprintUv * std::sqrt(double(w) * h);
    return across > 0 ? std::log2(std::fmin(across, 1e30)) : 0.0;
}

Rgb trilinear(const std::vector<MipLevel>& chain, double u, double v, double footprintUv) {
    double level = std::fmin(std::fmax(lodLevel(footprintUv, chain[0].width, chain[0].height), 0.0), double(chain.size() - 1));
    int l0 = int(std::floor(level));
    double f = level - l0;
    Rgb c0 = bilinear(chain[size_t(l0)], u, v);
    if (f <= 0 || l0 + 1 >= int(chain.size())) return c0;
    Rgb c1 = bilinear(chain[size_t(l0) + 1], u, v);
    return {(1 - f) * c0.r + f * c1.r, (1 - f) * c0.g + f * c1.g, (1 - f) * c0.b + f * c1.b};
}

// NumOctaves: n = Σ_{k<N} 2^-k noise(2^k s p), then absval |n| or linear (n + 1)/2.
double perlinValue(double x, double y, double z, double scale, int octaves, bool absval) {
    double n = 0;
    for (int k = 0; k < octaves; ++k) {
        double f = std::ldexp(scale, k);
        n += std::ldexp(1.0, -k) * perlinNoise(f * x, f * y, f * z);
    }
    return absval ? std::fabs(n) : 0.5 * (n + 1);
}

const char* kTextureKernel = R"CLC(
__kernel void eval_test(const __global float4* texels, const __global ImageInfo* images,
                        const __global TextureMap* tex, const __global float4* q, __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    float4 a = q[i];
    float3 c = Texture_Eval(tex, images, texels, a.xy, (float3)(0.0f), a.xyz * 3.0f, a.z);
    float level = -1.0f;
#ifdef CLRT_HAS_MIPMAPS
    ImageInfo base = images[tex->image];
    level = Mip_Level(a.z, base.width, base.height);
#endif
    out[i] = (float4)(c, level);
}
)CLC";

// A scene with one textured quad: `textureXml` is its TextureMap (id 1) and the image is tex.png.
std::string quadScene(const std::string& textureXml) {
    return std::string(R"(<Scene><Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
<ImageName>q.png</ImageName></Camera></Cameras>
<Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
<Textures><Images><Image id="1">tex.png</Image></Images>)") + textureXml + R"(</Textures>
<VertexData>-1 -1 0 1 -1 0 1 1 0 -1 1 0</VertexData><TexCoordData>0 0 1 0 1 1 0 1</TexCoordData>
<Objects><Mesh id="1"><Material>1</Material><Textures>1</Textures><Faces>1 2 3 1 3 4</Faces></Mesh></Objects></Scene>)";
}

// Runs eval_test over the queries (u, v, footprint) with the scene's first texture.
std::vector<dev::float4> evalOnDevice(const DeviceScene& ds, const std::vector<dev::float4>& q, const char* extraDefine) {
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"textures.cl"});
    sources.push_back({"eval_test.cl", kTextureKernel});
    std::vector<std::string> defines = {"-DCLRT_HAS_TEXTURES=1"};
    if (extraDefine) defines.push_back(extraDefine);
    cl::Program program = buildProgramFromSources(dc, sources, defines);
    cl::Kernel k = CL_CPP(cl::Kernel(program, "eval_test"));
    cl::Context& ctx = dc.context();
    auto ro = [&](const void* p, size_t bytes) {
        return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(p)));
    };
    cl::Buffer texels = ro(ds.texels.data(), ds.texels.size() * sizeof(dev::float4));
    cl::Buffer images = ro(ds.images.data(), ds.images.size() * sizeof(dev::ImageInfo));
    cl::Buffer tex = ro(ds.textures.data(), sizeof(dev::TextureMap));
    cl::Buffer qb = ro(q.data(), q.size() * sizeof(dev::float4));
    std::vector<dev::float4> out(q.size());
    cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
    int n = int(q.size());
    k.setArg(0, texels); k.setArg(1, images); k.setArg(2, tex); k.setArg(3, qb); k.setArg(4, ob); k.setArg(5, n);
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
    CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
    return out;
}

double rmse(const ImageRGB& a, const ImageRGB& b) {
    double se = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) se += double(a.pixels[i] - b.pixels[i]) * (a.pixels[i] - b.pixels[i]);
    return std::sqrt(se / double(a.pixels.size()));
}

double rmseRows(const ImageRGB& a, const ImageRGB& b, int y0, int y1) {
    double se = 0;
    size_t n = 0;
    for (size_t i = size_t(y0) * a.width * 3; i < size_t(y1) * a.width * 3; ++i, ++n)
        se += double(a.pixels[i] - b.pixels[i]) * (a.pixels[i] - b.pixels[i]);
    return std::sqrt(se / double(n));
}

}  // namespace

TEST_CASE("NumOctaves and Interpolation trilinear are read from XML and JSON; a bad count is one error", "[textures][scene]") {
    TempDir dir;
    std::vector<unsigned char> rgb(3, 0);
    writePng8(dir.file("tex.png"), 1, 1, rgb);
    const std::string maps = R"(<TextureMap id="1" type="image"><ImageId>1</ImageId><Interpolation>trilinear</Interpolation>
</TextureMap><TextureMap id="2" type="perlin"><NumOctaves>4</NumOctaves></TextureMap>)";
    std::string xml = quadScene(maps);
    writeFileBytes(dir.file("a.xml"), xml);
    Scene s = loadScene(dir.file("a.xml"));
    REQUIRE(s.textures.size() == 2);
    CHECK(s.textures[0].interpolation == dev::INTERP_TRILINEAR);
    CHECK(s.textures[1].numOctaves == 4);
    CHECK(s.textures[0].numOctaves == 1);  // default
    writeFileBytes(dir.file("a.json"), R"({"Scene": {"Materials": {"Material": {"_id": "1"}},
 "Textures": {"Images": {"Image": {"_id": "1", "_data": "tex.png"}},
   "TextureMap": [{"_id": "1", "_type": "image", "ImageId": "1", "Interpolation": "trilinear"},
                  {"_id": "2", "_type": "perlin", "NumOctaves": "3"}]}}})");
    Scene j = loadScene(dir.file("a.json"));
    REQUIRE(j.textures.size() == 2);
    CHECK(j.textures[0].interpolation == dev::INTERP_TRILINEAR);
    CHECK(j.textures[1].numOctaves == 3);
    for (const char* bad : {"0", "17", "2.5"}) {
        std::string b = xml;
        b.replace(b.find("<NumOctaves>4"), 13, std::string("<NumOctaves>") + bad);
        writeFileBytes(dir.file("b.xml"), b);
        try {
            loadScene(dir.file("b.xml"));
            FAIL("no error for NumOctaves " << bad);
        } catch (const Error& e) {
            std::string msg = e.what();
            INFO(msg);
            CHECK(msg.find("b.xml:") != std::string::npos);
            CHECK(msg.find("NumOctaves") != std::string::npos);
            CHECK(msg.find('\n') == std::string::npos);
        }
    }
}

TEST_CASE("mip pyramid: box filter over each texel's exact footprint, odd sizes keep the mean", "[textures]") {
    MipLevel l0;
    l0.width = 37;
    l0.height = 23;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 255);
    for (int i = 0; i < l0.width * l0.height; ++i) l0.texels.push_back({u(rng), u(rng), u(rng), 0});
    auto mean = [](const MipLevel& l) {
        double s = 0;
        for (const auto& t : l.texels) s += t.x + 2 * t.y + 3 * t.z;
        return s / double(l.texels.size());
    };
    std::vector<MipLevel> chain = mipPyramid(l0);
    REQUIRE(chain.size() == 5);  // 18×11, 9×5, 4×2, 2×1, 1×1
    CHECK(chain[0].width == 18);
    CHECK(chain[0].height == 11);
    CHECK(chain.back().width == 1);
    CHECK(chain.back().height == 1);
    for (const MipLevel& l : chain) CHECK(std::fabs(mean(l) - mean(l0)) < 1e-3 * mean(l0));
    // an even image: each texel is the mean of its 2×2 block, per channel
    MipLevel e;
    e.width = 4;
    e.height = 2;
    for (int i = 0; i < 8; ++i) e.texels.push_back({float(i), float(10 * i), float(i * i), 0});
    MipLevel h = mipDownsample(e);
    REQUIRE(h.width == 2);
    REQUIRE(h.height == 1);
    CHECK(h.texels[0].x == Approx((0 + 1 + 4 + 5) / 4.0));
    CHECK(h.texels[1].y == Approx(10 * (2 + 3 + 6 + 7) / 4.0));
    CHECK(h.texels[1].z == Approx((4 + 9 + 36 + 49) / 4.0));
    // a row of 3 → 1: the mean of the three (each weighs 1/3), not the middle texel
    MipLevel t;
    t.width = 3;
    t.height = 1;
    t.texels = {{3, 0, 0, 0}, {6, 0, 0, 0}, {30, 0, 0, 0}};
    CHECK(mipDownsample(t).texels[0].x == Approx(13.0));
}

TEST_CASE("trilinear: the device's level of detail and lookup match the host reference", "[textures][cl]") {
    TempDir dir;
    // 37×23 random texels (a non-power-of-two chain)
    const int w = 37, hgt = 23;
    std::vector<unsigned char> rgb(size_t(w) * hgt * 3);
    std::mt19937 rng(11);
    for (auto& c : rgb) c = (unsigned char)(rng() % 256);
    writePng8(dir.file("tex.png"), w, hgt, rgb);
    writeFileBytes(dir.file("s.xml"), quadScene(R"(<TextureMap id="1" type="image"><ImageId>1</ImageId>
<Interpolation>trilinear</Interpolation><DecalMode>replace_kd</DecalMode></TextureMap>)"));
    DeviceScene ds = flattenScene(loadScene(dir.file("s.xml")));
    REQUIRE(ds.features.mipMaps);
    REQUIRE(ds.textures[0].mipLevels == 6);  // 37×23 … 1×1
    const std::vector<std::string> defines = ds.features.defines();
    CHECK(std::find(defines.begin(), defines.end(), "-DCLRT_HAS_MIPMAPS=1") != defines.end());
    MipLevel l0;
    l0.width = w;
    l0.height = hgt;
    for (size_t i = 0; i < rgb.size(); i += 3) l0.texels.push_back({float(rgb[i]), float(rgb[i + 1]), float(rgb[i + 2]), 0});
    std::vector<MipLevel> chain = mipPyramid(l0);
    chain.insert(chain.begin(), l0);
    std::uniform_real_distribution<float> uv(-2, 3), lg(-12, 4);
    std::vector<dev::float4> q;
    for (int i = 0; i < 4000; ++i) q.push_back({uv(rng), uv(rng), std::exp2(lg(rng)), 0});
    q.push_back({0.3f, 0.4f, 0.0f, 0});          // no footprint: level 0 (bilinear)
    q.push_back({0.3f, 0.4f, INFINITY, 0});      // infinite: the coarsest level
    q.push_back({0.3f, 0.4f, NAN, 0});           // NaN: level 0
    std::vector<dev::float4> out = evalOnDevice(ds, q, "-DCLRT_HAS_MIPMAPS=1");
    double worstLevel = 0, worstColour = 0;
    int levelsSeen[6] = {0, 0, 0, 0, 0, 0};
    for (size_t i = 0; i < q.size(); ++i) {
        double fp = q[i].z;
        if (std::isfinite(fp) && fp > 0) worstLevel = std::fmax(worstLevel, std::fabs(out[i].w - lodLevel(fp, w, hgt)));
        Rgb ref = trilinear(chain, q[i].x, q[i].y, std::isnan(fp) ? 0.0 : fp);
        double err = std::fmax(std::fabs(out[i].x - ref.r / 255), std::fmax(std::fabs(out[i].y - ref.g / 255), std::fabs(out[i].z - ref.b / 255)));
        worstColour = std::fmax(worstColour, err);
        double lv = std::fmin(std::fmax(lodLevel(std::isnan(fp) ? 0.0 : fp, w, hgt), 0.0), 5.0);
        ++levelsSeen[int(lv)];
    }
    WARN("trilinear: worst |level - host| " << worstLevel << ", worst colour error " << worstColour);
    CHECK(worstLevel < 1e-4);
    CHECK(worstColour < 2e-5);  // float vs double on 0..1 values
    for (int l = 0; l < 6; ++l) CHECK(levelsSeen[l] > 0);
    // the infinite footprint is the 1×1 level: the image's mean
    Rgb mean = bilinear(chain.back(), 0, 0);
    CHECK(out[q.size() - 2].x == Approx(mean.r / 255).epsilon(1e-5));
    // without CLRT_HAS_MIPMAPS (or bilinear): the level-0 bilinear lookup, footprint ignored
    std::vector<dev::float4> flat = evalOnDevice(ds, q, nullptr);
    double worstFlat = 0;
    for (size_t i = 0; i < q.size(); ++i) {
        Rgb ref = bilinear(l0, q[i].x, q[i].y);
        worstFlat = std::fmax(worstFlat, std::fabs(flat[i].x - ref.r / 255));
    }
    CHECK(worstFlat < 2e-5);
}

TEST_CASE("NumOctaves: the device's fractal Perlin sum matches the host reference", "[textures][cl]") {
    TempDir dir;
    std::vector<unsigned char> rgb(3, 0);
    writePng8(dir.file("tex.png"), 1, 1, rgb);
    for (const char* conv : {"linear", "absval"})
        for (int octaves : {1, 2, 5}) {
            std::string t = std::string(R"(<TextureMap id="1" type="perlin"><DecalMode>replace_kd</DecalMode><NoiseConversion>)") +
                            conv + "</NoiseConversion><NoiseScale>0.7</NoiseScale><NumOctaves>" + std::to_string(octaves) +
                            "</NumOctaves></TextureMap>";
            writeFileBytes(dir.file("s.xml"), quadScene(t));
            DeviceScene ds = flattenScene(loadScene(dir.file("s.xml")));
            REQUIRE(ds.textures[0].octaves == octaves);
            std::mt19937 rng(13);
            std::uniform_real_distribution<float> x(-5, 5);
            std::vector<dev::float4> q;
            for (int i = 0; i < 3000; ++i) q.push_back({x(rng), x(rng), x(rng), 0});
            std::vector<dev::float4> out = evalOnDevice(ds, q, nullptr);  // pObj = 3·(x, y, z)
            double worst = 0;
            for (size_t i = 0; i < q.size(); ++i) {
                double ref = perlinValue(3.0 * q[i].x, 3.0 * q[i].y, 3.0 * q[i].z, 0.7, octaves, conv[0] == 'a');
                ref = std::fmin(1.0, std::fmax(0.0, ref));
                worst = std::fmax(worst, std::fabs(out[i].x - ref));
            }
            INFO(conv << ", " << octaves << " octaves: worst " << worst);
            CHECK(worst < 2e-4);
        }
}

TEST_CASE("NumOctaves 1 renders the plain Perlin texture, byte for byte", "[textures][render]") {
    std::string xml = readFileBytes(std::string(CLRT_SOURCE_DIR) + "/scenes/perlin_octaves.xml");
    REQUIRE(!xml.empty());
    TempDir dir;
    auto render = [&](const std::string& text) {
        writeFileBytes(dir.file("p.xml"), text);
        Scene s = loadScene(dir.file("p.xml"));
        return renderCamera(s, s.cameras.at(0), 1, 0);
    };
    // the scene with every <NumOctaves> removed, and with every one set to 1
    std::string none = xml, ones = xml;
    for (size_t at; (at = none.find("<NumOctaves>")) != std::string::npos;) none.erase(at, none.find("</NumOctaves>", at) + 13 - at);
    for (size_t at = 0; (at = ones.find("<NumOctaves>", at)) != std::string::npos; at += 12)
        ones[at + 12] = '1';
    ImageRGB a = render(none), b = render(ones), c = render(xml);
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
    CHECK(rmse(a, c) > 1.0);  // the octaves do change the other spheres
}

TEST_CASE("far checkerboard plane at 1 spp: trilinear is far closer to the filtered image than bilinear",
          "[textures][render]") {
    const std::string path = std::string(CLRT_SOURCE_DIR) + "/scenes/mip_checker_plane.xml";
    std::string xml = readFileBytes(path);
    REQUIRE(xml.find("<Interpolation>trilinear</Interpolation>") != std::string::npos);
    TempDir dir;
    writeFileBytes(dir.file("mip_checker.png"), readFileBytes(std::string(CLRT_SOURCE_DIR) + "/scenes/mip_checker.png"));
    auto render = [&](const char* interp, int spp, uint32_t seed) {
        std::string text = xml;
        size_t at = text.find("trilinear</Interpolation>");
        text.replace(at, 9, interp);
        writeFileBytes(dir.file("m.xml"), text);
        Scene s = loadScene(dir.file("m.xml"));
        return renderCamera(s, s.cameras.at(0), spp, seed);
    };
    ImageRGB ref = render("bilinear", 256, 1), ref2 = render("bilinear", 256, 2);
    ImageRGB nearest = render("nearest", 1, 0), bilinear = render("bilinear", 1, 0), trilinear = render("trilinear", 1, 0);
    const double noise = rmse(ref, ref2) / std::sqrt(2.0);  // the reference's own noise (one render)
    const double eNearest = rmse(nearest, ref), eBilinear = rmse(bilinear, ref), eTrilinear = rmse(trilinear, ref);
    // the far plane: rows 44-62 of 108 (from the horizon to ~12 units away; the plane is minified there)
    const double fNearest = rmseRows(nearest, ref, 44, 63), fBilinear = rmseRows(bilinear, ref, 44, 63);
    const double fTrilinear = rmseRows(trilinear, ref, 44, 63);
    WARN("far checkerboard, RMSE (8-bit units) against 256-spp bilinear, whole image / far plane: nearest "
         << eNearest << " / " << fNearest << ", bilinear " << eBilinear << " / " << fBilinear << ", trilinear "
         << eTrilinear << " / " << fTrilinear << "; reference noise " << noise);
    CHECK(noise < 0.1 * eTrilinear);  // the reference is converged well below the errors compared
    // Whole image: the near plane is magnified (every lookup is level 0 there) and its 1-spp check edges
    // are as aliased as bilinear's; trilinear's isotropic footprint cannot follow the grazing plane's
    // anisotropy in between (docs/scene-format.md, "Trilinear textures").
    CHECK(eTrilinear < 0.6 * eBilinear);
    CHECK(eTrilinear < 0.45 * eNearest);
    CHECK(fTrilinear < 0.4 * fBilinear);
    CHECK(fTrilinear < 0.35 * fNearest);
}

namespace {
// The checkerboard of scenes/mip_checker.png on a plane at height `texY` (quad over x ∈ [-200, 200],
// z ∈ [-400, 5]), seen from (0, 1, 4) toward the horizon; with `mirrorFloor`, a mirror covers y = 0.
std::string mirrorScene(const char* interp, float texY, bool mirrorFloor) {
    std::string y = std::to_string(texY);
    // ShadowRayEpsilon 0: the reflected ray starts at the robust offset, as close to the mirror as a ray can,
    // so the mirror shows the ceiling exactly where the plane at -texY shows (at the course's 1e-3 the
    // reflected view is lifted by it: RMSE 1.86 against 0.02 x 73.4 allowed).
    std::string s = std::string(R"(<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>2</MaxRecursionDepth><ShadowRayEpsilon>0</ShadowRayEpsilon>
<Cameras><Camera id="1" type="lookAt"><Position>0 1 4</Position><GazePoint>0 0.6 -10</GazePoint><Up>0 1 0</Up>
<FovY>40</FovY><NearDistance>1</NearDistance><ImageResolution>192 108</ImageResolution><ImageName>m.png</ImageName></Camera></Cameras>
<Lights><AmbientLight>0 0 0</AmbientLight></Lights>
<Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material>
<Material id="2" type="mirror"><AmbientReflectance>0 0 0</AmbientReflectance><DiffuseReflectance>0 0 0</DiffuseReflectance>
<SpecularReflectance>0 0 0</SpecularReflectance><MirrorReflectance>1 1 1</MirrorReflectance></Material></Materials>
<Textures><Images><Image id="1">mip_checker.png</Image></Images><TextureMap id="1" type="image"><ImageId>1</ImageId>
<Interpolation>)") + interp + R"(</Interpolation><DecalMode>replace_all</DecalMode></TextureMap></Textures>
<VertexData>-200 )" + y + " 5  200 " + y + " 5  200 " + y + " -400  -200 " + y + R"( -400  -200 0 5  200 0 5  200 0 -400  -200 0 -400</VertexData>
<TexCoordData>0 0  100 0  100 101.25  0 101.25  0 0 0 0 0 0 0 0</TexCoordData>
<Objects><Mesh id="1"><Material>1</Material><Textures>1</Textures><Faces>1 2 3 1 3 4</Faces></Mesh>)";
    if (mirrorFloor) s += R"(<Mesh id="2"><Material>2</Material><Faces>5 6 7 5 7 8</Faces></Mesh>)";
    return s + "</Objects></Scene>";
}
}  // namespace

TEST_CASE("trilinear through a planar mirror: the cone keeps its width over the bounce", "[textures][render]") {
    TempDir dir;
    writeFileBytes(dir.file("mip_checker.png"), readFileBytes(std::string(CLRT_SOURCE_DIR) + "/scenes/mip_checker.png"));
    auto render = [&](const std::string& xml) {
        writeFileBytes(dir.file("m.xml"), xml);
        Scene s = loadScene(dir.file("m.xml"));
        return renderCamera(s, s.cameras.at(0), 1, 0);
    };
    // The ceiling at y = 2 seen in the floor mirror is the plane at y = -2 seen directly: the same uv,
    // incidence and path length at every pixel below the horizon (rows 56..107).
    ImageRGB viaMirror = render(mirrorScene("trilinear", 2, true)), direct = render(mirrorScene("trilinear", -2, false));
    ImageRGB bilinear = render(mirrorScene("bilinear", -2, false));
    const double eMirror = rmseRows(viaMirror, direct, 56, 108), eFilter = rmseRows(bilinear, direct, 56, 108);
    WARN("mirror vs direct (trilinear), RMSE " << eMirror << "; bilinear vs trilinear " << eFilter);
    CHECK(eFilter > 10.0);          // the filtering matters in these rows
    CHECK(eMirror < 0.02 * eFilter);  // and the mirrored lookups filter as the direct ones do
}
