// Flattening of the scene model into device arrays (see device_scene.h): world-space triangles with
// their shading data (flat or area-weighted smooth normals, uvs), spheres with their affine maps,
// materials, textures and the texel atlas, lights, the BVH over all primitives, and the feature set.
#include "render/device_scene.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <system_error>
#include <thread>
#include <cmath>
#include <map>

#include "image/image.h"
#include "render/env_distribution.h"
#include "shared/type_tables.h"
#include "util/error.h"

namespace clrt {
namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void storeRows(dev::float4 rows[3], const Mat4& m) {
    for (int r = 0; r < 3; ++r)
        rows[r] = {float(m.m[r][0]), float(m.m[r][1]), float(m.m[r][2]), float(m.m[r][3])};
}

}  // namespace

bool FeatureSet::bounces() const {
    for (const auto& row : materialTypes())
        if (row.bounces && has(row.kind)) return true;
    return false;
}

std::vector<std::string> FeatureSet::defines() const {
    std::vector<std::string> d;
    auto add = [&](bool on, const char* name) {
        if (on && *name) d.push_back(std::string("-D") + name + "=1");
    };
    for (const auto& row : lightTypes()) add(has(row.kind), row.flag);
    for (const auto& row : materialTypes()) add(has(row.kind), row.flag);
    add(textures, "CLRT_HAS_TEXTURES");
    add(spheres, "CLRT_HAS_SPHERES");
    add(primRefsIdentity, "CLRT_PRIMREFS_IDENTITY");
    // Rounded up to a multiple of 8 so that scenes of similar depth share a cached program.
    if (bvhStack > 0) d.push_back("-DCLRT_BVH4_STACK_SIZE=" + std::to_string((bvhStack + 7) / 8 * 8));
    return d;
}

dev::CameraParams makeCameraParams(const Camera& cam) {
    dev::CameraParams c{};
    c.position = toFloat4(cam.position);
    c.u = toFloat4(cam.u);
    c.v = toFloat4(cam.v);
    c.w = toFloat4(cam.w);
    c.nearPlane = {cam.left, cam.right, cam.bottom, cam.top};
    c.nearDistance = cam.nearDistance;
    c.focusDistance = cam.focusDistance;
    c.apertureSize = cam.apertureSize;
    c.width = cam.width;
    c.height = cam.height;
    setSamplesPerPixel(c, cam.numSamples);
    return c;
}

void setSamplesPerPixel(dev::CameraParams& c, int spp) {
    c.spp = std::max(1, spp);
    // Strata: the largest divisor of spp not above sqrt(spp), so 100 -> 10x10, 7 -> 1x7.
    int sx = 1;
    for (int d = 1; d * d <= c.spp; ++d)
        if (c.spp % d == 0) sx = d;
    c.strataX = c.spp / sx;
    c.strataY = sx;
}

namespace {

// The triangles of one mesh shape in world space, in index order (degenerate and non-finite ones
// counted and left out). Independent per shape, so shapes are flattened on several threads.
struct MeshTriangles {
    std::vector<dev::Triangle> triangles;
    std::vector<dev::TriangleShading> shading;
    std::vector<Aabb> boxes;
    size_t degenerate = 0, nonFinite = 0;
};

void flattenMesh(const Scene& scene, const Shape& s, int texSet, MeshTriangles& out) {
    const MeshData& mesh = scene.meshes.at(s.meshIndex);
    out.triangles.reserve(mesh.indices.size() / 3);
    out.shading.reserve(mesh.indices.size() / 3);
    out.boxes.reserve(mesh.indices.size() / 3);
    std::vector<Vec3> pw(mesh.positions.size());
    for (size_t v = 0; v < pw.size(); ++v) pw[v] = s.transform.transformPoint(mesh.positions[v]);
    // Smooth shading: given normals (transformed by the inverse transpose) or area-weighted ones.
    std::vector<Vec3> nw;
    if (s.smooth) {
        nw.assign(pw.size(), Vec3(0, 0, 0));
        if (mesh.normals.size() == mesh.positions.size()) {
            Mat4 inv;
            Mat4 invT = s.transform.inverse(inv) ? inv.transposed() : Mat4::identity();
            for (size_t v = 0; v < nw.size(); ++v) nw[v] = normalize(invT.transformVector(mesh.normals[v]));
        } else {
            for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
                int a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
                Vec3 n = cross(pw[b] - pw[a], pw[c] - pw[a]);  // length = 2·area: area weighting
                if (!isFinite(n)) continue;
                nw[a] += n; nw[b] += n; nw[c] += n;
            }
            for (Vec3& n : nw) n = normalize(n);
        }
    }
    bool hasUv = mesh.uvs.size() == mesh.positions.size();
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        int a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        const Vec3 &p0 = pw[a], &p1 = pw[b], &p2 = pw[c];
        if (!isFinite(p0) || !isFinite(p1) || !isFinite(p2)) { ++out.nonFinite; continue; }
        Vec3 n = cross(p1 - p0, p2 - p0);
        float len = length(n);
        if (p0 == p1 || p1 == p2 || p0 == p2 || !(len > 0) || !std::isfinite(len)) {
            ++out.degenerate;
            continue;
        }
        n = n / len;
        dev::Triangle tri{toFloat4(p0), toFloat4(p1), toFloat4(p2)};
        dev::TriangleShading sh{};
        auto normalAt = [&](int v) { return (s.smooth && nw[v] != Vec3(0, 0, 0) && isFinite(nw[v])) ? nw[v] : n; };
        sh.n0 = toFloat4(normalAt(a));
        sh.n1 = toFloat4(normalAt(b));
        sh.n2 = toFloat4(normalAt(c));
        if (hasUv) {
            sh.uv01 = {mesh.uvs[a].x, mesh.uvs[a].y, mesh.uvs[b].x, mesh.uvs[b].y};
            sh.uv2 = {mesh.uvs[c].x, mesh.uvs[c].y, 0, 0};
        }
        sh.material = s.materialIndex;
        sh.textureSet = texSet;
        Aabb box;
        box.grow(p0); box.grow(p1); box.grow(p2);
        out.triangles.push_back(tri);
        out.shading.push_back(sh);
        out.boxes.push_back(box);
    }
}

}  // namespace

DeviceScene flattenScene(const Scene& scene) {
    auto t0 = std::chrono::steady_clock::now();
    DeviceScene ds;
    FeatureSet& f = ds.features;

    // ---- materials
    for (const Material& m : scene.materials) {
        dev::Material d{};
        d.ambient = toFloat4(m.ambient);
        d.diffuse = toFloat4(m.diffuse);
        d.specular = toFloat4(m.specular);
        d.mirror = toFloat4(m.mirror);
        d.absorption = toFloat4(m.absorptionCoefficient);
        d.phongExponent = m.phongExponent;
        d.refractionIndex = m.refractionIndex;
        d.absorptionIndex = m.absorptionIndex;
        d.roughness = m.roughness;
        d.kind = m.type;
        ds.materials.push_back(d);
    }
    if (ds.materials.empty()) ds.materials.push_back(dev::Material{});

    // ---- images (only those used) and textures
    std::map<int, int> imageSlot;  // scene image index -> device image index
    std::vector<bool> imageIsHdr;  // per device image
    auto useImage = [&](int sceneIndex) -> int {
        auto it = imageSlot.find(sceneIndex);
        if (it != imageSlot.end()) return it->second;
        auto ti = std::chrono::steady_clock::now();
        ImageRGB img = readImage(scene.imagePaths.at(sceneIndex));
        ds.imageSeconds += secondsSince(ti);
        dev::ImageInfo info{};
        info.offset = int(ds.texels.size());
        info.width = img.width;
        info.height = img.height;
        if (ds.texels.size() + size_t(img.width) * img.height > size_t(INT32_MAX))
            throw Error(scene.path + ": textures exceed 2^31 texels");
        const size_t n = size_t(img.width) * img.height;
        ds.texels.resize(size_t(info.offset) + n);
        dev::float4* dst = ds.texels.data() + info.offset;
        const float* src = img.pixels.data();
        for (size_t p = 0; p < n; ++p) dst[p] = {src[p * 3], src[p * 3 + 1], src[p * 3 + 2], 0};
        int slot = int(ds.images.size());
        ds.images.push_back(info);
        imageIsHdr.push_back(img.isHdr);
        imageSlot[sceneIndex] = slot;
        return slot;
    };
    ds.params.backgroundTexture = CLRT_INVALID;
    for (size_t ti = 0; ti < scene.textures.size(); ++ti) {
        const Texture& t = scene.textures[ti];
        dev::TextureMap d{};
        d.image = CLRT_INVALID;
        d.kind = t.type;
        d.decal = t.decalMode;
        // No mip-maps on the device: trilinear is filtered bilinearly.
        d.interpolation = t.interpolation == dev::INTERP_TRILINEAR ? dev::INTERP_BILINEAR : t.interpolation;
        d.normalizer = t.normalizer;
        d.bumpFactor = t.bumpFactor;
        d.scale = t.scale;
        d.offset = t.offset;
        d.noiseScale = t.noiseScale;
        d.noiseAbs = t.noiseConversion == "absval";
        d.blackColor = toFloat4(t.blackColor);
        d.whiteColor = toFloat4(t.whiteColor);
        if (t.type == dev::TEXTURE_IMAGE && t.imageIndex >= 0) {
            bool used = false;
            for (const Shape& s : scene.shapes)
                for (int x : s.textureIndices) used |= (x == int(ti));
            used |= t.decalMode == dev::DECAL_REPLACE_BACKGROUND;
            if (used) {
                d.image = useImage(t.imageIndex);
                if (!t.normalizerGiven)
                    d.normalizer = imageIsHdr[d.image] ? 1.0f : 255.0f;
            }
        }
        if (t.decalMode == dev::DECAL_REPLACE_BACKGROUND && d.image != CLRT_INVALID) ds.params.backgroundTexture = int(ti);
        if (t.decalMode == dev::DECAL_REPLACE_NORMAL || t.decalMode == dev::DECAL_BUMP_NORMAL)
            warnOnce(scene.path + ": texture id=" + std::to_string(t.id) +
                     ": normal/bump decal modes are not supported yet; ignored");
        ds.textures.push_back(d);
    }
    if (ds.textures.empty()) ds.textures.push_back(dev::TextureMap{});
    if (ds.images.empty()) ds.images.push_back(dev::ImageInfo{0, 1, 1, 0});
    if (ds.texels.empty()) ds.texels.push_back({0, 0, 0, 0});

    auto textureSetFor = [&](const Shape& s) -> int {
        if (s.textureIndices.empty()) return CLRT_INVALID;
        dev::TextureSet set;
        for (int k = 0; k < CLRT_MAX_TEXTURES_PER_SHAPE; ++k) set.texture[k] = CLRT_INVALID;
        int k = 0;
        for (int x : s.textureIndices) {
            if (scene.textures[x].decalMode == dev::DECAL_REPLACE_BACKGROUND) continue;
            if (k == CLRT_MAX_TEXTURES_PER_SHAPE) {
                warnOnce(s.source + ": more than 4 textures; the rest are ignored");
                break;
            }
            set.texture[k++] = x;
        }
        if (k == 0) return CLRT_INVALID;
        f.textures = true;
        ds.textureSets.push_back(set);
        return int(ds.textureSets.size()) - 1;
    };

    // ---- geometry
    std::vector<Aabb> boxes;
    std::vector<Aabb> sphereBoxes;
    size_t nanSkipped = 0;
    {
        size_t total = 0;
        for (const Shape& s : scene.shapes)
            if (s.type == ShapeType::Mesh) total += scene.meshes.at(s.meshIndex).indices.size() / 3;
        ds.triangles.reserve(total);
        ds.triangleShading.reserve(total);
        boxes.reserve(total + scene.shapes.size());
    }
    std::vector<std::pair<const Shape*, int>> meshJobs;  // (shape, texture set)
    for (const Shape& s : scene.shapes) {
        int texSet = textureSetFor(s);
        if (s.type == ShapeType::Plane) {
            Mat4 inv;
            Vec3 n = s.transform.inverse(inv) ? normalize(inv.transposed().transformVector(s.normal)) : Vec3(0, 0, 0);
            Vec3 p = s.transform.transformPoint(s.center);
            if (!(length(n) > 0) || !isFinite(n) || !isFinite(p)) {
                warn(s.source + ": singular transform or bad normal; plane skipped");
                continue;
            }
            dev::Plane pl{};
            pl.point = toFloat4(p);
            pl.normal = toFloat4(n);
            pl.material = s.materialIndex;
            pl.textureSet = texSet;
            ds.planes.push_back(pl);
            continue;
        }
        if (s.type == ShapeType::Sphere) {
            dev::Sphere sp{};
            sp.centerRadius = toFloat4(s.center, s.radius);
            Mat4 inv;
            if (!s.transform.inverse(inv) || !(s.radius > 0) || !isFinite(s.center)) {
                warn(s.source + ": singular transform or bad radius; sphere skipped");
                continue;
            }
            storeRows(sp.objectToWorld, s.transform);
            storeRows(sp.worldToObject, inv);
            sp.material = s.materialIndex;
            sp.textureSet = texSet;
            Aabb box;
            for (int c = 0; c < 8; ++c) {
                Vec3 corner(s.center.x + ((c & 1) ? s.radius : -s.radius), s.center.y + ((c & 2) ? s.radius : -s.radius),
                            s.center.z + ((c & 4) ? s.radius : -s.radius));
                box.grow(s.transform.transformPoint(corner));
            }
            ds.spheres.push_back(sp);
            sphereBoxes.push_back(box);
            continue;
        }
        meshJobs.push_back({&s, texSet});
    }
    // Meshes on all hardware threads (each job writes only its own result), then concatenated in
    // shape order: the same arrays as a sequential loop.
    {
        std::vector<MeshTriangles> results(meshJobs.size());
        std::atomic<size_t> next{0};
        const size_t threads = std::min<size_t>(meshJobs.size(), std::max(1u, std::thread::hardware_concurrency()));
        std::vector<std::exception_ptr> errors(std::max<size_t>(threads, 1));
        auto worker = [&](size_t t) {
            try {
                for (size_t j; (j = next++) < meshJobs.size();)
                    flattenMesh(scene, *meshJobs[j].first, meshJobs[j].second, results[j]);
            } catch (...) {
                errors[t] = std::current_exception();
                next = meshJobs.size();  // the others stop too
            }
        };
        std::vector<std::thread> pool;
        try {
            for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker, t);
        } catch (const std::system_error&) {  // no thread to be had: the others (and this one) do it
        }
        worker(0);
        for (std::thread& t : pool) t.join();
        for (const std::exception_ptr& e : errors)
            if (e) std::rethrow_exception(e);
        for (MeshTriangles& r : results) {
            ds.triangles.insert(ds.triangles.end(), r.triangles.begin(), r.triangles.end());
            ds.triangleShading.insert(ds.triangleShading.end(), r.shading.begin(), r.shading.end());
            boxes.insert(boxes.end(), r.boxes.begin(), r.boxes.end());
            ds.skippedTriangles += r.degenerate;
            nanSkipped += r.nonFinite;
        }
    }
    if (ds.skippedTriangles) warn(scene.path + ": skipped " + std::to_string(ds.skippedTriangles) + " degenerate triangles");
    if (nanSkipped) warn(scene.path + ": skipped " + std::to_string(nanSkipped) + " triangles with NaN/Inf vertices");
    ds.skippedTriangles += nanSkipped;
    f.spheres = !ds.spheres.empty();
    for (const Material& m : scene.materials) {
        f.add(m.type);
    }

    // ---- lights
    ds.params.envLight = CLRT_INVALID;
    for (const Light& l : scene.lights) {
        dev::Light d{};
        d.position = toFloat4(l.position);
        d.radiance = toFloat4(l.intensity);
        d.direction = toFloat4(normalize(l.direction));
        d.image = CLRT_INVALID;
        d.distribution = CLRT_INVALID;
        d.kind = l.type;
        f.add(l.type);
        switch (l.type) {
        case dev::LIGHT_POINT:
        case dev::LIGHT_DIRECTIONAL: break;
        case dev::LIGHT_SPOT: {
            float cov = std::clamp(l.coverageAngle, 0.0f, 360.0f), fall = std::clamp(l.falloffAngle, 0.0f, cov);
            d.cosCoverageHalf = std::cos(double(cov) * 0.5 * M_PI / 180.0);
            d.cosFalloffHalf = std::cos(double(fall) * 0.5 * M_PI / 180.0);
            break;
        }
        case dev::LIGHT_AREA: {
            Vec3 n = normalize(l.direction);
            Vec3 helper = std::fabs(n.x) > 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
            Vec3 u = normalize(cross(helper, n)), v = cross(n, u);
            d.edgeU = toFloat4(u * l.size);
            d.edgeV = toFloat4(v * l.size);
            d.area = l.size * l.size;
            break;
        }
        case dev::LIGHT_ENVIRONMENT: {
            d.radiance = {1, 1, 1, 0};
            d.direction = {0, 1, 0, 0};
            d.image = useImage(l.imageIndex);
            d.mapping = l.mapping;
            d.sampler = l.sampler;
            const dev::ImageInfo& info = ds.images[d.image];
            EnvMapView view{&ds.texels[info.offset], info.width, info.height, d.mapping};
            auto te = std::chrono::steady_clock::now();
            EnvDistribution dist = buildEnvDistribution(view);
            ds.envDistSeconds += secondsSince(te);
            d.distribution = int(ds.envDistribution.size());
            ds.envDistribution.insert(ds.envDistribution.end(), dist.data.begin(), dist.data.end());
            if (ds.params.envLight == CLRT_INVALID) {
                ds.params.envLight = int(ds.lights.size());
                ds.params.envScale = d.radiance;
                ds.params.envImage = d.image;
                ds.params.envMapping = d.mapping;
            } else {
                warnOnce(scene.path + ": several SphericalDirectionalLights: each lights the scene, but rays that "
                         "miss show the first one only");
            }
            break;
        }
        }
        ds.lights.push_back(d);
    }
    if (ds.lights.empty()) ds.lights.push_back(dev::Light{});  // never an empty buffer; numLights stays 0
    if (ds.envDistribution.empty()) ds.envDistribution.push_back(0.0f);

    // ---- BVH over triangles then spheres
    auto tb = std::chrono::steady_clock::now();
    boxes.insert(boxes.end(), sphereBoxes.begin(), sphereBoxes.end());
    ds.bvh = buildBvh(boxes);
    ds.bvh4 = collapseBvh4(ds.bvh);
    ds.features.bvhStack = std::max(1, ds.bvh4.maxStack);
    ds.bvhSeconds = secondsSince(tb);
    // Store triangles in BVH leaf order so a leaf's triangles are contiguous in memory.
    {
        const int numTris = int(ds.triangles.size());
        std::vector<dev::Triangle> tris(ds.triangles.size());
        std::vector<dev::TriangleShading> shading(ds.triangleShading.size());
        int next = 0;
        for (int& ref : ds.bvh.primRefs) {
            if (ref >= numTris) continue;  // spheres keep their indices
            tris[size_t(next)] = ds.triangles[size_t(ref)];
            shading[size_t(next)] = ds.triangleShading[size_t(ref)];
            ref = next++;
        }
        ds.triangles.swap(tris);
        ds.triangleShading.swap(shading);
        // Without spheres every reference is now its own position: the kernels can skip primRefs.
        bool identity = true;
        for (size_t i = 0; i < ds.bvh.primRefs.size() && identity; ++i) identity = ds.bvh.primRefs[i] == int(i);
        ds.features.primRefsIdentity = identity;
    }
    if (ds.triangles.empty()) { ds.triangles.push_back(dev::Triangle{}); ds.triangleShading.push_back(dev::TriangleShading{}); }
    if (ds.spheres.empty()) ds.spheres.push_back(dev::Sphere{});
    if (ds.planes.empty()) ds.planes.push_back(dev::Plane{});
    if (ds.textureSets.empty()) ds.textureSets.push_back(dev::TextureSet{{-1, -1, -1, -1}});

    dev::SceneParams& p = ds.params;
    p.background = toFloat4(scene.backgroundColor);
    p.ambient = toFloat4(scene.ambientLight);
    p.numTriangles = int(boxes.size() - sphereBoxes.size());
    p.numSpheres = int(sphereBoxes.size());
    p.numPlanes = int(ds.planes.size());
    p.numLights = int(scene.lights.size());  // every light is flattened (ds.lights holds a dummy when 0)
    p.maxDepth = std::max(0, scene.maxRecursionDepth);
    ds.flattenSeconds = secondsSince(t0) - ds.bvhSeconds;
    return ds;
}

}  // namespace clrt
