// The stratified sampler (cl_kernels/common.cl, Rng_Stratified2D; CLRT_PIXEL_SAMPLER_STRATIFIED): a host
// replica checked bit for bit against the device, then on the replica: the samples of a pixel form
// (0,m,2)-nets (one point in every elementary interval), each point alone is uniform over pixels (χ²),
// and two dimension pairs of one pixel are independent (the correlation of their coordinates). Then renders: the
// sampler changes noise, not expectation (a furnace), and `--sampler` reaches the kernels.
#include <catch.hpp>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <vector>

#include "cl/check.h"
#include "cl/program.h"
#include "flatten/device_scene.h"
#include "image/image.h"
#include "image/image_compare.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "sampler_reference.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {



// The host replica of Rng_Stratified2D, written from the definitions (radical inverse, the matrix
// above, nested uniform scrambling as reverse ∘ Laine–Karras ∘ reverse) rather than the device's
// shortcuts (its superset transform for Sobol's dimension, its single reversals).
// shuffleDim: take the index shuffle of another dimension pair (only the tests' no-padding variant).
Point stratified2D(uint32_t seed, int pixel, int sample, uint32_t pathId, uint32_t dim, const uint32_t* shuffleDim = nullptr) {
    uint32_t h = hashPcg(seed ^ 0x9e3779b9u);  // Rng_Key's strat
    h = hashPcg(h ^ uint32_t(pixel));
    h = hashPcg(h ^ pathId * 0x27d4eb2fu);
    const uint32_t sIdx = hashPcg(h ^ dim * 0x9e3779b1u);
    const uint32_t sX = hashPcg(sIdx ^ 0xa54ff53au), sY = hashPcg(sIdx ^ 0x510e527fu);
    const uint32_t idx = owen(uint32_t(sample), shuffleDim ? hashPcg(h ^ *shuffleDim * 0x9e3779b1u) : sIdx);
    return {owen(reverseBits(idx), sX), owen(sobol1(idx), sY)};
}


// Mean over 4096 pixels of r^2, r = the correlation over 16 samples of x in (path 1, dimA) with x in
// (pathB, dimB); sharedShuffle: B's point taken at A's shuffled index (what padding avoids).
double meanSquaredCorrelation(uint32_t dimA, uint32_t dimB, bool sharedShuffle, uint32_t pathB = 1u) {
    double sum = 0;
    for (int px = 0; px < 4096; ++px) {
        double xa[16], xb[16], ma = 0, mb = 0;
        for (int s = 0; s < 16; ++s) {
            Point a = stratified2D(11, px, s, 1u, dimA), b = stratified2D(11, px, s, pathB, dimB);
            if (sharedShuffle) b = stratified2D(11, px, s, pathB, dimB, &dimA);
            xa[s] = toFloat(a.x); xb[s] = toFloat(b.x); ma += xa[s] / 16; mb += xb[s] / 16;
        }
        double sab = 0, saa = 0, sbb = 0;
        for (int s = 0; s < 16; ++s) {
            sab += (xa[s] - ma) * (xb[s] - mb); saa += (xa[s] - ma) * (xa[s] - ma); sbb += (xb[s] - mb) * (xb[s] - mb);
        }
        sum += sab * sab / (saa * sbb);
    }
    return sum / 4096;
}

double chiSquare(const std::vector<int>& counts, double expected) {
    double c = 0;
    for (int k : counts) c += (k - expected) * (k - expected) / expected;
    return c;
}

}  // namespace

TEST_CASE("stratified sampler: the device's Rng_Stratified2D equals the host replica bit for bit", "[sampler][cl]") {
    const char* src = R"CLC(
__kernel void strat_test(const __global int4* in, __global float2* out, uint seed, int n) {
    int i = get_global_id(0);
    if (i < n) out[i] = Rng_Stratified2D(Rng_Key(seed, in[i].x, in[i].y, (uint)in[i].z), in[i].y, (uint)in[i].w);
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"common.cl"});
    sources.push_back({"strat_test.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, {});
    cl::Kernel k = CL_CPP(cl::Kernel(program, "strat_test"));
    std::vector<dev::int4> in;
    for (int pixel : {0, 1, 77, 123456, 2147483647})
        for (int sample : {0, 1, 2, 3, 15, 16, 255, 1000, 65535, 65536, 1048575})
            for (uint32_t pathId : {1u, 2u, 5u, 0x80000000u})
                for (uint32_t dim : {12u, 13u, 0x800cu, 37u, 0xffffffffu}) in.push_back({pixel, sample, int(pathId), int(dim)});
    const int n = int(in.size());
    std::vector<dev::float2> out(n);
    cl::Context& ctx = dc.context();
    cl::Buffer ib = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(dev::int4) * n, in.data()));
    cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, sizeof(dev::float2) * n));
    for (uint32_t seed : {0u, 7u, 2147483647u}) {
        k.setArg(0, ib); k.setArg(1, ob); k.setArg(2, seed); k.setArg(3, n);
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, sizeof(dev::float2) * n, out.data()));
        for (int i = 0; i < n; ++i) {
            const Point p = stratified2D(seed, in[i].x, in[i].y, uint32_t(in[i].z), uint32_t(in[i].w));
            INFO("seed " << seed << " pixel " << in[i].x << " sample " << in[i].y << " path " << in[i].z << " dim " << in[i].w);
            REQUIRE(out[i].x == toFloat(p.x));
            REQUIRE(out[i].y == toFloat(p.y));
            REQUIRE(out[i].x >= 0.0f);
            REQUIRE(out[i].x < 1.0f);
            REQUIRE(out[i].y < 1.0f);
        }
    }
}

TEST_CASE("stratified sampler: 2^m samples of a pixel from a multiple of 2^m form a (0,m,2)-net", "[sampler]") {
    for (int pixel : {0, 9, 40000})
        for (uint32_t dim : {12u, 0x800cu, 41u})
            for (int m = 0; m <= 10; ++m) {
                const int n = 1 << m;
                for (int block : {0, 1, 5}) {
                    std::vector<Point> p;
                    for (int s = block * n; s < (block + 1) * n; ++s) p.push_back(stratified2D(3, pixel, s, 1u, dim));
                    INFO("pixel " << pixel << " dim " << dim << " m " << m << " block " << block);
                    CHECK(isNet(p, m));
                }
            }
    // The check can fail: independent uniforms are no net (at 16 points, all 5 interval shapes).
    std::vector<Point> rnd;
    for (int s = 0; s < 16; ++s) rnd.push_back({hashPcg(2 * s), hashPcg(2 * s + 1)});
    CHECK_FALSE(isNet(rnd, 4));
}

TEST_CASE("stratified sampler: each point is uniform over pixels, and dimension pairs are independent (chi^2)", "[sampler]") {
    // 16x16 cells; 65536 pixels -> 256 expected per cell; χ² with 255 degrees of freedom: mean 255, sd
    // ~22.6; the 1e-4 tail is ~ 345.
    const int pixels = 65536;
    for (int sample : {0, 1, 6, 1000}) {
        std::vector<int> cells(256, 0);
        for (int px = 0; px < pixels; ++px) {
            const Point p = stratified2D(11, px, sample, 1u, 12u);
            ++cells[(p.x >> 28) * 16 + (p.y >> 28)];
        }
        INFO("sample " << sample);
        CHECK(chiSquare(cells, pixels / 256.0) < 345.0);
    }
    // Per pixel, the correlation of pair A's x with pair B's x over the pixel's 16 samples: pairs with
    // their own shuffles are paired at random, E[r^2] = 1/15 for a uniformly random pairing; pairs that
    // shared a shuffle (no padding) would be correlated in every pixel (checked: the test can fail).
    CHECK(meanSquaredCorrelation(12u, 0x800cu, false) < 0.12);
    CHECK(meanSquaredCorrelation(12u, 0x800cu, false) > 0.03);
    CHECK(meanSquaredCorrelation(12u, 0x800cu, true) > 0.3);
    // A child path (path id 2) is likewise independent of its parent's samples in the same dimensions.
    CHECK(meanSquaredCorrelation(12u, 12u, false, 2u) < 0.12);
}

namespace {

// A diffuse sphere on a ground quad under a latlong map with a broad gradient and a hot patch (a sky
// with a sun: importance and cosine samples both matter, and the ground holds soft shadows), MIS.
std::string skyScene(const std::string& map, int size) {
    std::ostringstream s;
    s << "<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>1</MaxRecursionDepth>"
      << "<Cameras><Camera id=\"1\" type=\"lookAt\"><Position>0 1 6</Position><GazePoint>0 0 0</GazePoint>"
      << "<Up>0 1 0</Up><FovY>40</FovY><NearDistance>1</NearDistance><ImageResolution>" << size << " " << size
      << "</ImageResolution><ImageName>out.exr</ImageName></Camera></Cameras>"
      << "<VertexData>-6 -1 -6  6 -1 -6  6 -1 6  -6 -1 6</VertexData>"
      << "<Materials><Material id=\"1\"><DiffuseReflectance>0.7 0.6 0.5</DiffuseReflectance></Material></Materials>"
      << "<Textures><Images><Image id=\"1\">" << map << "</Image></Images></Textures>"
      << "<Lights><SphericalDirectionalLight id=\"1\" type=\"latlong\" sampler=\"mis\"><ImageId>1</ImageId>"
      << "</SphericalDirectionalLight></Lights>"
      << "<Objects><Sphere id=\"1\"><Center>1</Center><Radius>1</Radius><Material>1</Material></Sphere>"
      << "<Mesh id=\"1\"><Material>1</Material><Faces>1 3 2  1 4 3</Faces></Mesh></Objects></Scene>";
    return s.str();
}

double imageMean(const ImageRGB& img) {
    double m = 0;
    for (float v : img.pixels) m += v;
    return m / double(img.pixels.size());
}

}  // namespace

TEST_CASE("stratified and zsobol samplers: less noise than independent samples, the same expectation", "[sampler][render]") {
    TempDir tmp;
    ImageRGB sky;
    sky.width = 64; sky.height = 32; sky.isHdr = true;
    sky.pixels.resize(size_t(64) * 32 * 3);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) sky.at(x, y, c) = (y < 16 ? 0.3f + 0.05f * y : 0.1f) + 0.1f * c + ((x / 4 == 3 && y / 4 == 1) ? 200.0f : 0.0f);
    writeExr(tmp.file("sky.exr"), sky);
    std::ofstream(tmp.file("sky.xml")) << skyScene(tmp.file("sky.exr"), 32);
    Scene scene = loadScene(tmp.file("sky.xml"));
    // Reference: 4096 independent samples; its own relMSE is ~1/256 of a 16-spp independent render's.
    const ImageRGB ref = renderCamera(scene, scene.cameras.at(0), 4096, 99, PixelSampler::Independent);
    const int spp = 16, runs = 8;
    double errS = 0, errI = 0, errZ = 0;
    ImageRGB meanS = ref;
    std::fill(meanS.pixels.begin(), meanS.pixels.end(), 0.0f);
    ImageRGB meanZ = meanS;
    for (int k = 0; k < runs; ++k) {
        const ImageRGB s = renderCamera(scene, scene.cameras.at(0), spp, uint32_t(k + 1), PixelSampler::Stratified);
        const ImageRGB i = renderCamera(scene, scene.cameras.at(0), spp, uint32_t(k + 1), PixelSampler::Independent);
        errS += relativeMse(s, ref) / runs;
        errI += relativeMse(i, ref) / runs;
        const ImageRGB z = renderCamera(scene, scene.cameras.at(0), spp, uint32_t(k + 1), PixelSampler::ZSobol);
        errZ += relativeMse(z, ref) / runs;
        for (size_t j = 0; j < s.pixels.size(); ++j) meanS.pixels[j] += s.pixels[j] / runs;
        for (size_t j = 0; j < z.pixels.size(); ++j) meanZ.pixels[j] += z.pixels[j] / runs;
    }
    const double errMean = relativeMse(meanS, ref);
    WARN("sky scene, " << spp << " spp: relMSE stratified " << errS << ", independent " << errI << " (ratio " << errI / errS
                       << "); mean of " << runs << " stratified renders " << errMean << "; image means " << imageMean(meanS)
                       << " / reference " << imageMean(ref));
    CHECK(errI / errS > 1.5);
    // Unbiased: averaging 8 independent stratified renders divides their error by ~8 (a bias would stay);
    // 0.25 leaves room for the reference's own noise.
    CHECK(errMean < 0.25 * errS);
    CHECK(imageMean(meanS) == Approx(imageMean(ref)).epsilon(0.003));
    const double errMeanZ = relativeMse(meanZ, ref);
    WARN("zsobol: relMSE " << errZ << " (independent / zsobol " << errI / errZ << "); mean of " << runs << " renders "
                           << errMeanZ << "; image mean " << imageMean(meanZ));
    CHECK(errI / errZ > 1.5);
    CHECK(errMeanZ < 0.25 * errZ);
    CHECK(imageMean(meanZ) == Approx(imageMean(ref)).epsilon(0.003));
}

TEST_CASE("clrt render --sampler: stratified by default, independent or zsobol on request, anything else a usage error", "[sampler][cli]") {
    TempDir d;
    ImageRGB sky;
    sky.width = 8; sky.height = 4; sky.isHdr = true;
    sky.pixels.assign(size_t(8) * 4 * 3, 1.0f);
    sky.at(2, 1, 0) = 50.0f;
    writeExr(d.file("sky.exr"), sky);
    std::ofstream(d.file("s.xml")) << skyScene(d.file("sky.exr"), 8);
    const std::string base = "render " + d.file("s.xml") + " -o " + d.path.string() + " --spp 4 --seed 2" + deviceArg();
    auto render = [&](const std::string& extra) { return renderedPixels(base + extra, d.file("log"), d.file("out.exr")); };
    const std::vector<float> def = render(""), strat = render(" --sampler stratified"), indep = render(" --sampler independent");
    CHECK(def == strat);
    CHECK(def != indep);
    const std::vector<float> z1 = render(" --sampler zsobol"), z2 = render(" --sampler zsobol");
    CHECK(z1 == z2);  // deterministic per seed
    CHECK(z1 != def);
    CHECK(z1 != indep);
    CHECK(render(" --sampler zsobol --seed 3") != z1);
    const int rc = runClrt(base + " --sampler sobol", d.file("log"));
    const CliResult r = cliResult(rc, readFileBytes(d.file("log")));
    CHECK(r.rc == 1);
    CHECK(r.errorLines == 1);
    CHECK(readFileBytes(d.file("log")).find("--sampler: expected stratified, independent, zsobol or correlated, got 'sobol'") != std::string::npos);
}

// The Z-ordered Sobol sampler's code is compiled only into programs that run it (CLRT_HAS_ZSOBOL): the
// kernel flags (-v) carry it exactly with --sampler zsobol, and a renderer whose program lacks it
// refuses the sampler instead of drawing from another one.
TEST_CASE("clrt render --sampler zsobol alone builds the kernels with CLRT_HAS_ZSOBOL; without it the renderer refuses zsobol", "[sampler][cli]") {
    TempDir d;
    ImageRGB sky;
    sky.width = 8; sky.height = 4; sky.isHdr = true;
    sky.pixels.assign(size_t(8) * 4 * 3, 1.0f);
    writeExr(d.file("sky.exr"), sky);
    std::ofstream(d.file("s.xml")) << skyScene(d.file("sky.exr"), 8);
    const std::string base = "render " + d.file("s.xml") + " -o " + d.path.string() + " --spp 4 -v" + deviceArg();
    for (const std::string sampler : {"stratified", "independent", "zsobol"}) {
        const int rc = runClrt(base + " --sampler " + sampler, d.file("log"));
        const std::string log = readFileBytes(d.file("log"));
        INFO(sampler << ": " << log);
        REQUIRE(rc == 0);
        REQUIRE(log.find("-DCLRT_HAS_") != std::string::npos);  // the flags are listed
        CHECK((log.find("-DCLRT_HAS_ZSOBOL=1") != std::string::npos) == (sampler == "zsobol"));
    }
    const Scene scene = loadScene(d.file("s.xml"));
    REQUIRE_FALSE(flattenScene(scene).features.zsobol);  // not a scene's feature
    CHECK(samplerRefusal(scene, PixelSampler::ZSobol).find("CLRT_HAS_ZSOBOL") != std::string::npos);
}

// Bits_Reverse (common.cl) in both of its forms: the shift-and-mask network every implementation but
// Oclgrind runs, and the byte table of quirk BIT_REVERSE_TABLE (CLRT_QUIRK_BIT_REVERSE_TABLE, which Oclgrind
// gets): both equal the host's bit reversal on edge patterns and 65536 pseudo-random words.
TEST_CASE("Bits_Reverse: the shift network and the quirk's byte table reverse alike", "[sampler][cl][quirks]") {
    const char* src = R"CLC(
__kernel void reverse_test(const __global uint* in, __global uint* out, int n) {
    int i = get_global_id(0);
    if (i < n) out[i] = Bits_Reverse(in[i]);
}
)CLC";
    std::vector<uint32_t> in = {0u, 1u, 0x80000000u, 0xffffffffu, 0x0000ffffu, 0x12345678u, 0xf0f0f0f0u, 0x55555555u};
    uint32_t x = 0x9e3779b9u;
    for (int i = 0; i < 65536; ++i) {
        x ^= x << 13; x ^= x >> 17; x ^= x << 5;
        in.push_back(x);
    }
    for (const std::vector<std::string>& defines : {std::vector<std::string>{}, std::vector<std::string>{"-DCLRT_QUIRK_BIT_REVERSE_TABLE"}}) {
        INFO("defines: " << (defines.empty() ? "none (the shift network)" : defines[0]));
        const std::vector<uint32_t> out = runElementwiseKernel<uint32_t>({"common.cl"}, "reverse_test", src, in, defines);
        const int n = int(in.size());
        int wrong = 0;
        for (int i = 0; i < n; ++i) wrong += out[size_t(i)] != reverseBits(in[size_t(i)]);
        CHECK(wrong == 0);
    }
}
