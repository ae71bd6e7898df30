// render_args.cpp — `clrt render`'s --help text and its options, parsed by the table of cli/args.h.
// Reads no scene element (--env-sampling names are checked against the env strategy table).
#include "cli/render_args.h"

#include "cli/args.h"
#include "flatten/memory_estimate.h"  // parseByteSize
#include "render/fused_renderer.h"  // parsePipeline
#include "scene/scene.h"            // kMaxSamplesPerPixel, parseEnvStrategy
#include "util/error.h"

namespace clrt {

const char* const kRenderHelp =
    "usage: clrt render SCENE [options]\n"
    "\n"
    "Renders every camera of SCENE (or one, with --camera) and writes each image under its ImageName\n"
    "into OUTDIR (.png: clamped and rounded; .exr: float radiance, plus one tone-mapped .png per\n"
    "Tonemap block of the camera: stem.png, or stem<Extension>.png / stem_<tmo>.png for several).\n"
    "Before any work, every output must be a plain file name ending in .png/.exr, no two alike, none\n"
    "of them a file the scene reads (exit 2), and OUTDIR must accept a new file (exit 4).\n"
    "Ctrl-C (or SIGTERM) ends the render after its current pass and writes the partial image (the EXR's\n"
    "spp attribute says how many samples it has); a second one exits at once.\n"
    "\n"
    "options:\n"
    "  -o, --output DIR      output directory (default: the current directory); must exist\n"
    "  --device SPEC         OpenCL device: an index from `clrt devices`, cpu (PoCL's CPU\n"
    "                        device(s) when several CPU implementations are installed), gpu, a name\n"
    "                        substring, platform:NAME (every device of a platform whose name\n"
    "                        contains NAME, e.g. platform:portable = PoCL, platform:intel), `all`,\n"
    "                        or a comma list (0,2) to render on several devices at once\n"
    "                        (default: the first GPU, else the CPU device)\n"
    "  --spp N               samples per pixel (1 to 1048576), overriding each camera's NumSamples\n"
    "  --seed N              random seed (default 0); the same seed gives the same image\n"
    "  --sampler S           stratified (default): camera jitter, light and BSDF samples stratified\n"
    "                        over a pixel's samples (scrambled (0,2)-sequence); independent: every\n"
    "                        number drawn independently (the noise of a plain Monte Carlo renderer);\n"
    "                        zsobol: every dimension (jitter, lens, time, picks, light, BSDF, roulette)\n"
    "                        from one Owen-scrambled Sobol sequence in Z order over the pixels;\n"
    "                        correlated: stratified, but each camera sample's one 2D point is its\n"
    "                        pixel jitter, its lens point and the classic renderer's light samples at\n"
    "                        the camera ray's hit, as the course's renderer drew them until 2022 (its 2020 and\n"
    "                        2022 references; biased, for comparing with them: docs/scene-format.md)\n"
    "  --instancing M        how meshes placed several times are stored: auto (default: once, under\n"
    "                        their own BVH, where their placements hold >= 2^20 triangles), flatten\n"
    "                        (every triangle in world space), two-level (every mesh that is no light\n"
    "                        once; the same image within float rounding)\n"
    "  --mesh-light-sampling M  how LightMesh lights are sampled: solid-angle (default: a triangle, picked\n"
    "                        by how much of the shading point's view it fills in a mesh of at most 16,\n"
    "                        by area in a larger one, none an enclosed light hides from the point; then\n"
    "                        a direction uniform in its solid angle) or area (a triangle by area, then a\n"
    "                        uniform point on it, as the course's renderer: noisier, the same expectation;\n"
    "                        for comparing noise with the course's references)\n"
    "  --rr-rule R           Russian roulette of RussianRoulette cameras: unbiased (default), or course:\n"
    "                        the course's hw6 references' biased rule (a hit's own light is counted\n"
    "                        undivided when the path dies there; see docs/scene-format.md); ignored\n"
    "                        by MultipleImportanceSampling cameras\n"
    "  --backface-culling C  whether the classic renderer's camera, reflection and outside rays skip\n"
    "                        triangles seen from behind: auto (default: on for scenes in the 2025 JSON\n"
    "                        form, whose course references cull, off for XML scenes), on or off\n"
    "  --vertex-normals W    smooth shading's face-normal weights at a vertex without given normals:\n"
    "                        auto or area (default: by area, as the course's references since 2022),\n"
    "                        or unweighted (as its 2020 references)\n"
    "  --ray-origin O        what camera rays see between the eye and the image plane: auto (default:\n"
    "                        they start at the eye but skip triangles seen from behind there, as the\n"
    "                        course's references show), eye (everything) or plane (nothing: pinhole\n"
    "                        rays start on the image plane)\n"
    "  --target-error X      render in passes until the estimated relMSE of the image is <= X (> 0):\n"
    "                        even and odd passes form two independent half-images, and their\n"
    "                        difference estimates the error (relative to 1, or to 255 for .png\n"
    "                        outputs); the camera's NumSamples is ignored, --spp (>= 4) caps the\n"
    "                        samples. Prints the estimate, the spp and the time, and writes them into\n"
    "                        the EXR header (relMseEstimate, spp, renderTime, stopReason)\n"
    "  --time-limit S        the same passes until the next pair of passes would end after S seconds\n"
    "                        (per camera; at least one pair); with --target-error, whichever comes\n"
    "                        first. Neither: the image is rendered as before, bit for bit\n"
    "  --camera ID           render only the camera with this id\n"
    "  --resolution WxH      render every camera at W x H pixels (same view) instead of its\n"
    "                        ImageResolution: tiny renders for checking kernels (oclgrind)\n"
    "  --ldr-quantize MODE   floor (default) or round: how .png outputs turn clamped radiance into\n"
    "                        8 bits; floor is what the course's reference renders do\n"
    "  --env-sampling S      strategy of every SphericalDirectionalLight: uniform, cosine, importance or\n"
    "                        mis (default: the scene's sampler=, else mis)\n"
    "  --pipeline P          fused (one kernel per sample pass), lanes (fused, four paths per\n"
    "                        work-item in vector lanes: path-traced scenes, and direct lighting\n"
    "                        under an environment map, no dielectric split (<= 4 spp), motion\n"
    "                        blur or mip-maps; else fused), wavefront (a kernel per\n"
    "                        stage) or auto (default: lanes where they can and some surface is\n"
    "                        Lambertian or an environment map is sampled by mis, else\n"
    "                        fused, on CPU devices for images of >= 1024 pixels; wavefront\n"
    "                        otherwise); the image is the same either way (lanes: up to\n"
    "                        rounding); -v says which rendered\n"
    "  --all-features        build the kernels with every feature, not only what the scene uses\n"
    "                        (for measuring what specialisation gains)\n"
    "  --exr-half            write .exr outputs with half-float channels (default: float)\n"
    "  --part K/N            render only tile set K of N (every N-th tile from the K-th) of each\n"
    "                        camera into OUTDIR/<ImageName>.part<K>of<N>.exr; `clrt merge` joins them\n"
    "  --checkpoint DIR      keep every finished tile in DIR; the same command run again renders only\n"
    "                        the tiles still missing (same image, bit for bit)\n"
    "  --tile-pixels N       pixels per tile of --part, --checkpoint and MPI renders (default: 1/64\n"
    "                        of the image, 4096 to 65536)\n"
    "  --max-memory SIZE     refuse (exit 2, before flattening) a scene whose estimated host peak or\n"
    "                        memory per device exceeds SIZE (e.g. 512M, 4G; K/M/G/T = powers of\n"
    "                        1024); without it the limits are the devices' own and the machine's\n"
    "                        available memory; -v prints the estimate\n"
    "  --preview [ADDR:]PORT serve a live preview page while rendering (default address 127.0.0.1;\n"
    "                        PORT 0: any free port); the URL, with its access token, is printed on\n"
    "                        stderr. The page shows each camera's image as passes complete (with\n"
    "                        --target-error/--time-limit; otherwise when a camera is done), tone-map\n"
    "                        controls, and Stop (= Ctrl-C). A port in use: exit 1 before rendering.\n"
    "                        See docs/preview.md (SSH port forwarding, security)\n"
    "  --preview-keep        after the render, keep serving the preview until Ctrl-C (default: the\n"
    "                        process ends as without --preview, once an open page has the final state)\n"
    "  --display-server H:P  stream each camera's image to the tev viewer at H:P (tev's protocol, as\n"
    "                        pbrt-v4 speaks it); tev not running: one warning, the render goes on\n"
    "  -v, --verbose         print the kernel build flags and other details\n"
    "  -h, --help            this text\n"
    "\n"
    "MPI: `mpirun -np N clrt render SCENE ...` renders one image over N ranks (the scene at the same\n"
    "path on each): rank 0 hands out tiles, renders too, and writes the outputs; --device applies per\n"
    "rank. A rank that fails ends the job and nothing is written; with --checkpoint a rerun goes on.\n"
    "\n"
    "limits: at most 1048576 samples per pixel and a MaxRecursionDepth of 256; larger scene values\n"
    "are capped with a warning naming the scene file.\n";

static_assert(kMaxSamplesPerPixel == 1048576 && kMaxRecursionDepth == 256, "update kRenderHelp and README");

RenderArgs parseRenderArgs(int argc, char** argv, int start) {
    RenderArgs a;
    using Str = const std::string&;
    a.positional = parseArgs(argc, argv, start, {
        flagOption({"-h", "--help"}, a.help),
        textOption({"-o", "--output"}, a.outDir),
        textOption({"--device"}, a.device),
        {{"--spp"}, true, [&](Str f, Str v) { a.spp = parseIntArg(f, v, 1, kMaxSamplesPerPixel); }},
        {{"--seed"}, true, [&](Str f, Str v) { a.seed = uint32_t(parseIntArg(f, v, 0, 2147483647)); }},
        {{"--sampler"}, true, [&](Str f, Str v) {
             if (!parsePixelSampler(v, a.pixelSampler)) throwExpected(f, "stratified, independent, zsobol or correlated", v);
         }},
        {{"--instancing"}, true, [&](Str f, Str v) {
             if (v == "auto") a.instancing = Instancing::Auto;
             else if (v == "flatten") a.instancing = Instancing::Flatten;
             else if (v == "two-level") a.instancing = Instancing::TwoLevel;
             else throwExpected(f, "auto, flatten or two-level", v);
         }},
        {{"--mesh-light-sampling"}, true, [&](Str f, Str v) {
             a.meshLightsByArea = parseChoiceArg(f, v, {"solid-angle", "area"}) == 1;
         }},
        {{"--rr-rule"}, true, [&](Str f, Str v) {
             if (!parseRouletteRule(v, a.rouletteRule)) throwExpected(f, "unbiased or course", v);
         }},
        {{"--backface-culling"}, true, [&](Str f, Str v) {
             a.backfaceCulling = int(parseChoiceArg(f, v, {"auto", "off", "on"})) - 1;
         }},
        {{"--vertex-normals"}, true, [&](Str f, Str v) {
             a.vertexNormals = int(parseChoiceArg(f, v, {"auto", "area", "unweighted"})) - 1;
         }},
        {{"--ray-origin"}, true, [&](Str f, Str v) { a.rayOrigin = int(parseChoiceArg(f, v, {"auto", "eye", "plane"})) - 1; }},
        textOption({"--camera"}, a.cameraId),
        {{"--target-error"}, true, [&](Str f, Str v) { a.stop.targetError = parseBoundedArg(f, v, 0, true); }},
        {{"--time-limit"}, true, [&](Str f, Str v) { a.stop.timeLimit = parseBoundedArg(f, v, 0, false); }},
        {{"--resolution"}, true, [&](Str f, Str v) {
             const auto wh = splitArg(f, v, 'x', "WxH");
             a.width = parseIntArg(f, wh.first, 1, 1 << 16);
             a.height = parseIntArg(f, wh.second, 1, 1 << 16);
         }},
        flagOption({"-v", "--verbose"}, a.verbose),
        textOption({"--preview"}, a.previewAddress),
        flagOption({"--preview-keep"}, a.previewKeep),
        textOption({"--display-server"}, a.displayServer),
        flagOption({"--exr-half"}, a.exrHalf),
        textOption({"--checkpoint"}, a.dist.checkpointDir),
        {{"--tile-pixels"}, true, [&](Str f, Str v) { a.dist.tilePixels = size_t(parseIntArg(f, v, 1, 1 << 24)); }},
        {{"--part"}, true, [&](Str f, Str v) {
             const auto kn = splitArg(f, v, '/', "K/N");
             a.dist.parts = parseIntArg(f, kn.second, 1, 1 << 20);
             a.dist.part = parseIntArg(f, kn.first, 1, a.dist.parts);
         }},
        flagOption({"--all-features"}, a.allFeatures),
        {{"--max-memory"}, true, [&](Str f, Str v) {
             if (!parseByteSize(v, a.maxMemory)) throwExpected(f, "a size such as 512M or 4G", v);
         }},
        {{"--pipeline"}, true, [&](Str f, Str v) {
             if (!parsePipeline(v, a.pipeline)) throwExpected(f, "fused, lanes, wavefront or auto", v);
         }},
        {{"--env-sampling"}, true, [&](Str f, Str v) {
             dev::EnvStrategy es;
             if (!parseEnvStrategy(v, es)) throwExpected(f, "uniform, cosine, importance or mis", v);
             a.envStrategy = v;
         }},
        {{"--ldr-quantize"}, true, [&](Str f, Str v) {
             a.truncatePng = parseChoiceArg(f, v, {"round", "floor"}) == 1;
         }},
    }, "render");
    return a;
}

std::string pixelOptions(const RenderArgs& a) {
    return "env=" + a.envStrategy + ";all-features=" + std::to_string(a.allFeatures) +
           ";sampler=" + pixelSamplerName(a.pixelSampler) +
           (a.rouletteRule == RouletteRule::Course ? ";rr-rule=course" : "") +
           (a.meshLightsByArea ? ";mesh-light-sampling=area" : "") +
           (a.backfaceCulling >= 0 ? ";backface-culling=" + std::to_string(a.backfaceCulling) : "") +
           (a.vertexNormals >= 0 ? ";vertex-normals=" + std::to_string(a.vertexNormals) : "") +
           (a.rayOrigin >= 0 ? ";ray-origin=" + std::to_string(a.rayOrigin) : "") +
           ";resolution=" + std::to_string(a.width) + "x" + std::to_string(a.height) +
           ";tile=" + std::to_string(a.dist.tilePixels);
}

}  // namespace clrt
