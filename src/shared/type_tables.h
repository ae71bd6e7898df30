// type_tables.h — the host's view of the enum tables of device_types.h: each enum's names (scene
// files, command line), and for lights, materials and BRDFs the kernel feature flag and whether the type
// spawns child rays. The scene readers (src/scene/read_*.cpp), the command line, the flattener and
// FeatureSet (src/flatten/) all read these; nothing else lists a type's name or flag.
#pragma once
#include <string>
#include <vector>

#include "shared/device_types.h"

namespace clrt {

template <class Kind> struct TypeRow {
    Kind kind;
    const char* constant;    // the enum constant's name, e.g. "LIGHT_POINT"
    const char* name;        // in scene files / on the command line
    const char* flag = "";   // lights, materials, BRDFs: kernel feature flag, "" if always compiled
    bool bounces = false;    // materials: spawns reflection/refraction children
};
template <class Kind> using TypeTable = std::vector<TypeRow<Kind>>;

#define CLRT_TYPE_ROW_L_(K, NAME, FLAG) {dev::K, #K, NAME, FLAG, false},
#define CLRT_TYPE_ROW_M_(K, NAME, FLAG, BOUNCES) {dev::K, #K, NAME, FLAG, BOUNCES != 0},
#define CLRT_TYPE_ROW_N_(K, NAME) {dev::K, #K, NAME},
inline const TypeTable<dev::LightKind>& lightTypes() {
    static const TypeTable<dev::LightKind> t = {CLRT_LIGHT_TABLE(CLRT_TYPE_ROW_L_)};
    return t;
}
inline const TypeTable<dev::MaterialKind>& materialTypes() {
    static const TypeTable<dev::MaterialKind> t = {CLRT_MATERIAL_TABLE(CLRT_TYPE_ROW_M_)};
    return t;
}
inline const TypeTable<dev::BrdfKind>& brdfTypes() {
    static const TypeTable<dev::BrdfKind> t = {CLRT_BRDF_TABLE(CLRT_TYPE_ROW_L_)};
    return t;
}
inline const TypeTable<dev::EnvMappingKind>& envMappings() {
    static const TypeTable<dev::EnvMappingKind> t = {CLRT_ENV_MAPPING_TABLE(CLRT_TYPE_ROW_N_)};
    return t;
}
inline const TypeTable<dev::EnvStrategy>& envStrategies() {
    static const TypeTable<dev::EnvStrategy> t = {CLRT_ENV_STRATEGY_TABLE(CLRT_TYPE_ROW_N_)};
    return t;
}
inline const TypeTable<dev::TextureKind>& textureTypes() {
    static const TypeTable<dev::TextureKind> t = {CLRT_TEXTURE_TABLE(CLRT_TYPE_ROW_N_)};
    return t;
}
inline const TypeTable<dev::DecalKind>& decalModes() {
    static const TypeTable<dev::DecalKind> t = {CLRT_DECAL_TABLE(CLRT_TYPE_ROW_N_)};
    return t;
}
inline const TypeTable<dev::InterpKind>& interpolations() {
    static const TypeTable<dev::InterpKind> t = {CLRT_INTERP_TABLE(CLRT_TYPE_ROW_N_)};
    return t;
}
inline const TypeTable<dev::TmoKind>& tonemapOperators() {
    static const TypeTable<dev::TmoKind> t = {CLRT_TMO_TABLE(CLRT_TYPE_ROW_N_)};
    return t;
}
#undef CLRT_TYPE_ROW_L_
#undef CLRT_TYPE_ROW_M_
#undef CLRT_TYPE_ROW_N_

// The row named `name` (exact match; callers lower-case where the format is case-insensitive), or null.
template <class Kind> const TypeRow<Kind>* findType(const TypeTable<Kind>& table, const std::string& name) {
    for (const TypeRow<Kind>& r : table)
        if (name == r.name) return &r;
    return nullptr;
}
// Sets `out` to the kind named `name`; false (out untouched) if no row has that name.
template <class Kind> bool lookupType(const TypeTable<Kind>& table, const std::string& name, Kind& out) {
    const TypeRow<Kind>* r = findType(table, name);
    if (r) out = r->kind;
    return r != nullptr;
}
// The row of `kind` (every enum value has one).
template <class Kind> const TypeRow<Kind>& typeRow(const TypeTable<Kind>& table, Kind kind) {
    return table.at(size_t(kind));  // rows are in enum order (the enums are generated from the tables)
}
// "a, b or c": the names, for messages.
template <class Kind> std::string typeNames(const TypeTable<Kind>& table) {
    std::string s;
    for (size_t i = 0; i < table.size(); ++i)
        s += (i == 0 ? "" : i + 1 == table.size() ? " or " : ", ") + std::string(table[i].name);
    return s;
}

}  // namespace clrt
