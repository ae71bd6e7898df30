// Named transformations of a scene (<Transformations>: Translation, Scaling, Rotation, Composite, each
// with an id) and the composition of an object's reference string such as "t1 s2 r1 c1". References
// apply in the order written: "t1 s2" means first t1 then s2, so M = S2 * T1 (points are columns).
// Filled by the scene walker; no XML here.
#pragma once
#include <map>
#include <string>

#include "util/math.h"

namespace clrt {

struct TransformTable {
    std::map<int, Mat4> translations, scalings, rotations, composites;
};

// Composes `refs` (whitespace-separated tokens: t|s|r|c followed by an id, case-insensitive) into one
// object->world matrix. An empty string gives the identity. Throws clrt::Error "<where>: ..." for a
// malformed token or an undefined id.
Mat4 composeTransforms(const std::string& refs, const TransformTable& table, const std::string& where);

// Rotation of angleDeg degrees about (ax, ay, az), counter-clockwise looking from +axis to the origin.
Mat4 makeRotation(double angleDeg, double ax, double ay, double az);
// A row-major 4x4 from 16 numbers.
Mat4 makeComposite(const double v[16]);
// The determinant of m's linear (upper-left 3x3) part: its volume scale, negative for a mirror.
double linearDeterminant(const Mat4& m);
// Whether m's linear part is a similarity (a rotation, possibly mirrored, times one scale): MᵀM = (tr/3)·I
// within relTol·tr, tr = trace(MᵀM) > 0.
bool isSimilarity(const Mat4& m, double relTol = 1e-9);

}  // namespace clrt
