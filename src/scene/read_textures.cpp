// Textures: <Textures> with its <Images> (Image: id and a path, resolved against the scene file's
// folder) and <TextureMap> elements (attributes id, type = image|perlin|checkerboard, degamma):
//   ImageId Interpolation DecalMode Normalizer BumpFactor (image textures, bump mapping)
//   NoiseConversion NoiseScale NumOctaves BlackColor WhiteColor Scale Offset (procedural textures).
// Interpolation is nearest, bilinear or trilinear (mip-mapped, 2025); NumOctaves (Perlin, 2025) is 1..16.
// All Images of a <Textures> are read before its TextureMaps. Objects name TextureMaps by id
// (read_objects.cpp), SphericalDirectionalLight names an Image (read_lights.cpp, imageRef).
#include <filesystem>

#include "scene/scene_walker.h"
#include "shared/type_tables.h"

namespace clrt::walker {
namespace {

// Past 16 octaves the terms are below float precision of the first (2^-16) and the lattice of the last
// is 65536 times finer.
constexpr int kMaxOctaves = 16;

void readImage(Walker& w, const SceneNode& img) {
    int id = requiredId(img);
    std::string p = trim(img.text());
    if (p.empty()) fail(img, describe(img) + " has no path");
    if (!w.imageIds.emplace(id, int(w.scene.imagePaths.size())).second)
        fail(img, "duplicate Image id " + std::to_string(id));
    w.scene.imagePaths.push_back(w.resolve(p));
}

void readImages(Walker& w, const SceneNode& n) { w.readInTableOrder(n, {{"Image", readImage}}); }

// The type and degamma attributes.
void readTextureKind(const SceneNode& n, Texture& t) {
    auto typeAttr = n.attribute("type");
    if (!typeAttr) fail(n, describe(n) + " has no type attribute (image, perlin or checkerboard)");
    std::string type = lower(trim(*typeAttr));
    if (!lookupType(textureTypes(), type, t.type)) fail(n, describe(n) + ": unknown texture type '" + *typeAttr + "'");
    if (auto d = n.attribute("degamma")) t.degamma = boolean(n, *d, describe(n) + ": degamma");
}

// ImageId (image textures), Interpolation, DecalMode, Normalizer (default 1 for EXR and HDR images).
void readTextureLookup(const Walker& w, const SceneNode& n, Texture& t) {
    if (t.type == dev::TEXTURE_IMAGE) t.imageIndex = imageRef(w, n, *need(n, "ImageId"));
    if (auto c = n.child("Interpolation")) {
        std::string v = lower(trim(c->text()));
        if (!lookupType(interpolations(), v, t.interpolation))
            fail(*c, "<Interpolation>: unknown value '" + trim(c->text()) + "' (nearest, bilinear, trilinear)");
    }
    if (auto c = n.child("DecalMode")) {
        std::string v = lower(trim(c->text()));
        if (!lookupType(decalModes(), v, t.decalMode)) fail(*c, "<DecalMode>: unknown value '" + trim(c->text()) + "'");
    }
    if (auto c = n.child("Normalizer")) {
        t.normalizer = number(*c);
        t.normalizerGiven = true;
        if (t.normalizer <= 0) fail(*c, "<Normalizer> must be positive");
    } else if (t.type == dev::TEXTURE_IMAGE) {
        std::string ext = lower(std::filesystem::path(w.scene.imagePaths[size_t(t.imageIndex)]).extension().string());
        if (ext == ".exr" || ext == ".hdr") t.normalizer = 1;
    }
}

// BumpFactor and the procedural textures' parameters.
void readTextureScalars(const SceneNode& n, Texture& t) {
    if (auto c = n.child("BumpFactor")) t.bumpFactor = number(*c);
    if (auto c = n.child("NoiseConversion")) {
        std::string v = lower(trim(c->text()));
        if (v != "linear" && v != "absval")
            fail(*c, "<NoiseConversion>: unknown value '" + trim(c->text()) + "' (linear or absval)");
        t.noiseConversion = v;
    }
    if (auto c = n.child("NoiseScale")) t.noiseScale = number(*c);
    if (auto c = n.child("NumOctaves")) {
        t.numOctaves = integer(*c);
        if (t.numOctaves < 1 || t.numOctaves > kMaxOctaves)
            fail(*c, "<NumOctaves> must be 1.." + std::to_string(kMaxOctaves));
    }
    if (auto c = n.child("BlackColor")) t.blackColor = vec3(*c);
    if (auto c = n.child("WhiteColor")) t.whiteColor = vec3(*c);
    if (auto c = n.child("Scale")) t.scale = number(*c);
    if (auto c = n.child("Offset")) t.offset = number(*c);
}

void readTextureMap(Walker& w, const SceneNode& n) {
    w.checkChildren(n, {"ImageId", "Interpolation", "DecalMode", "Normalizer", "BumpFactor", "NoiseConversion",
                        "NoiseScale", "NumOctaves", "BlackColor", "WhiteColor", "Scale", "Offset"});
    Texture t;
    t.id = requiredId(n);
    readTextureKind(n, t);
    readTextureLookup(w, n, t);
    readTextureScalars(n, t);
    if (!w.textureIds.emplace(t.id, int(w.scene.textures.size())).second)
        fail(n, "duplicate TextureMap id " + std::to_string(t.id));
    w.scene.textures.push_back(t);
}

}  // namespace

void readTextures(Walker& w, const SceneNode& n) {
    w.readInTableOrder(n, {{"Images", readImages}, {"TextureMap", readTextureMap}});
}

int imageRef(const Walker& w, const SceneNode& owner, const SceneNode& idNode) {
    int id = integer(idNode);
    auto it = w.imageIds.find(id);
    if (it == w.imageIds.end()) fail(idNode, describe(owner) + " references undefined Image " + std::to_string(id));
    return it->second;
}

}  // namespace clrt::walker
