// Named transformations: <Transformations> and its Translation, Scaling, Rotation and Composite
// elements, each with a unique id per kind, into Walker::transforms (transforms.h), where objects'
// <Transformations> strings ("t1 s2 r1") look them up (transformOf: objects, cameras, lights).
#include <cstddef>

#include "scene/scene_walker.h"

namespace clrt::walker {
namespace {

Mat4 translation(const SceneNode& n) { return Mat4::translation(vec3(n)); }
Mat4 scaling(const SceneNode& n) { return Mat4::scaling(vec3(n)); }
// Angle in degrees, then the axis.
Mat4 rotation(const SceneNode& n) {
    auto v = numbers(n, 4);
    Mat4 m = makeRotation(v[0], v[1], v[2], v[3]);
    if (v[1] == 0 && v[2] == 0 && v[3] == 0) fail(n, describe(n) + ": rotation axis is zero");
    return m;
}
// Sixteen numbers, row by row.
Mat4 composite(const SceneNode& n) {
    auto v = numbers(n, 16);
    return makeComposite(v.data());
}

// The elements of <Transformations>: name, where they are kept, how their text becomes a matrix.
struct TransformKind {
    const char* name;
    std::map<int, Mat4> TransformTable::*map;
    Mat4 (*matrix)(const SceneNode& n);
};
const TransformKind kTransformKinds[] = {
    {"Translation", &TransformTable::translations, translation},
    {"Scaling", &TransformTable::scalings, scaling},
    {"Rotation", &TransformTable::rotations, rotation},
    {"Composite", &TransformTable::composites, composite},
};

}  // namespace

void readTransformations(Walker& w, const SceneNode& n) {
    std::vector<std::string> known;
    for (const TransformKind& k : kTransformKinds) known.push_back(k.name);
    w.checkChildren(n, known);
    for (auto& c : n.children()) {
        std::string name = c->name();
        for (const TransformKind& k : kTransformKinds) {
            if (name != k.name) continue;
            Mat4 m = k.matrix(*c);
            int id = requiredId(*c);
            if (!(w.transforms.*k.map).emplace(id, m).second)
                fail(*c, "duplicate " + name + " id " + std::to_string(id));
        }
    }
}

Mat4 transformOf(const Walker& w, const SceneNode& owner) {
    auto t = owner.child("Transformations");
    if (!t) return Mat4::identity();
    return composeTransforms(t->text(), w.transforms, t->location() + ": " + describe(owner));
}

}  // namespace clrt::walker
