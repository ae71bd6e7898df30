"""to_mitsuba_path.py — the path-tracing part of bench/to_mitsuba.py (Converter(..., path_tracing=True)):
what a path-traced course scene (hw6) needs beyond the direct-lighting conversion. Used by
bench/bench_mitsuba_path.py; reads the camera's MaxRecursionDepth and RendererParams, the scene's
<BRDFs>, Materials (type mirror/conductor/dielectric, Transparency, MirrorReflectance, RefractionIndex,
AbsorptionIndex, DiffuseReflectance, SpecularReflectance, degamma), LightMesh, LightSphere, MeshInstance
and AreaLight.

Conventions (clrt's, docs/scene-format.md "Path tracing" and cl_kernels/path.cl, and how they map):
- Depth: clrt's MaxRecursionDepth d is the camera ray plus at most d bounces, and next-event estimation
  (NEE, MIS) still samples the lights at the last vertex: the longest path has d + 2 segments. Mitsuba's
  max_depth counts segments (1: emitters seen directly; 2: direct light), so max_depth = d + 2 with NEE
  or MIS, d + 1 without (clrt's BSDF-only strategies end at the last vertex's emission).
  bench/bench_mitsuba_path.py --depth-check measures it.
- Russian roulette: clrt's (RussianRoulette) lifts the depth cap, which Mitsuba's rr_depth cannot
  match; the comparison runs without it and Mitsuba's is disabled (rr_depth = max_depth + 1).
- Diffuse: f = kd/π in normalized Modified(Blinn)Phong and TorranceSparrow (Mitsuba ρ = kd), kd in the
  other BRDFs and in classic materials (ρ = π·kd). A ρ above 1 is a raw 1x1 bitmap (Mitsuba's rgb
  reflectance refuses it).
- A material with a specular lobe (SpecularReflectance > 0: Phong, Blinn-Phong, Torrance-Sparrow as the
  course defines them, or a classic material's Blinn-Phong) is rendered in Mitsuba by the plugin
  coursebrdf (bench/mitsuba_course_brdf.py: clrt's formulas in Dr.Jit; Mitsuba 3 has no Phong, and its
  roughconductor/roughplastic are GGX/Beckmann microfacets with another shape and Fresnel); without one,
  by Mitsuba's diffuse (as before the plugin: the same images).
- Image textures of inline meshes (TexCoordData; replace_kd, blend_kd, replace_ks; nearest or bilinear;
  degamma and Normalizer as clrt applies them): bitmaps of the linear texel values (textured_bsdf; kd and ks
  of coursebrdf, or the diffuse reflectance), uvs shifted by half a texel for bilinear lookups (clrt's
  texel corners at integer u·w, Mitsuba's centres). The hw4 wood box path traced (replace_kd and
  replace_ks, bilinear; 64², 2048 spp each) agrees within 0.01% in the mean, relMSE between the two 0.0023
  (noise); a diffuse copy with degamma and nearest lookups 0.04%, with blend_kd 0.01%.
- Not mapped (warned, dropped on the Mitsuba side, so a benchmark scene should have none of them): other
  textures (procedural, bump and normal maps, replace_all, on spheres, PLY meshes and instances);
  Roughness (clrt perturbs the mirror direction uniformly in a square, not a microfacet law); a
  dielectric's AbsorptionCoefficient (Beer's law needs a medium, which `path` does not trace).
- Mirror: conductor material "none" times MirrorReflectance. Conductor: conductor with eta =
  RefractionIndex, k = AbsorptionIndex (Mitsuba's exact complex Fresnel; clrt's formula is the course's
  approximation, equal at normal incidence). Dielectric (and the older Transparency form): dielectric
  int_ior = RefractionIndex, ext_ior = 1. A specular material that also has kd or ks is, in clrt, the
  sum of its specular child and its non-specular part, each picked with probability 1/2: in Mitsuba a
  blendbsdf of weight 0.5 of twice each. Opaque BSDFs are two-sided, as clrt's path tracer is.
- Emission: clrt's LightMesh and AreaLight emit from both faces, Mitsuba's area emitter from the front
  only. A closed LightMesh (every edge shared by two faces) gets each face turned to point away from the
  mesh's centroid (exact for convex light boxes; the inside is closed off anyway); an open one is two
  copies offset by ±1e-4 of its size, facing away from each other, unless the converter is told
  open_lights="outward" (scene_dict): then it is turned outwards like a closed one. That is for an open
  box whose opening other geometry closes (the hw6 light box: five faces under the ceiling), whose inner
  side lights only its own inside: the same image, and Mitsuba samples the same area as clrt (the two
  copies double it, and the light samples that land on the inner copy are lost: +32% relMSE on the hw6
  box at 64 spp, docs/studies/2026-12-04-path-noise-vs-mitsuba.md). An AreaLight (not geometry in clrt)
  is two such rectangles with a black BSDF: in Mitsuba they occlude and the camera sees them (clrt's do
  neither; no benchmark scene shows either). LightSphere: a sphere with an area emitter (outside); an
  ellipsoidal one (not a similarity: Mitsuba's sphere cannot be one) a fine mesh with the ellipsoid's normals
  (to_mitsuba.Converter.sphere_shape, as for any Sphere) emitting a constant radiance outwards, which is
  physical but not the course's convention that clrt follows (an ellipsoid lights the scene as its object-space
  sphere does: docs/scene-format.md): the means disagree, and the bench says so. A hw6-like glossy box with a
  (1.6, 1.6, 0.5) ellipsoid: Mitsuba/clrt 0.97 in the mean, 0.5-2.8x by region; clrt's own LightMesh of the
  same tessellation agrees with Mitsuba (0.973 / 0.972 / 0.958 against 0.972 / 0.973 / 0.958).
"""
import math

import numpy as np


def _nums(el, default=None):
    if el is None or el.text is None or not el.text.strip():
        return default
    return [float(x) for x in el.text.split()]


def _camera(c):
    return c.root.find("Cameras")[0]


def clrt_depth(c):
    """The first camera's MaxRecursionDepth (its own, else the scene's, else clrt's default 6)."""
    for el in (_camera(c).find("MaxRecursionDepth"), c.root.find("MaxRecursionDepth")):
        if el is not None and el.text and el.text.strip():
            return min(256, int(el.text))
    return 6


def renderer_params(c):
    el = _camera(c).find("RendererParams")
    return set((el.text or "").split()) if el is not None else set()


def integrator(c):
    """Mitsuba's path with clrt's depth (see the module comment) and no roulette."""
    params = renderer_params(c)
    r = _camera(c).find("Renderer")
    if r is None or (r.text or "").strip() != "PathTracing":
        c.warn("the camera is not path traced in clrt (no <Renderer>PathTracing): the images will differ")
    mis = {"MultipleImportanceSampling", "MIS_POWER", "MIS_BALANCE", "MIS_01"}  # clrt's, and the 2025 form's
    nee = bool(params & ({"NextEventEstimation"} | mis))
    if "RussianRoulette" in params:
        c.warn("RussianRoulette: clrt's roulette lifts the depth cap; Mitsuba renders without roulette at the cap")
    if not params & mis:
        c.warn("RendererParams '%s': Mitsuba's path always uses MIS (same expectation %s)" % (
            " ".join(sorted(params)), "as clrt's NEE" if nee else "only without point lights"))
    max_depth = clrt_depth(c) + (2 if nee else 1)
    return {"type": "path", "max_depth": max_depth, "rr_depth": max_depth + 1, "hide_emitters": False}


# ------------------------------------------------------------------------------------------- materials
def diffuse_scale(c, mat):
    """1 where the material's diffuse term is kd/π (normalized Modified(Blinn)Phong, TorranceSparrow), π
    where it is kd (the other BRDFs and classic materials)."""
    bid = mat.get("BRDF")
    brdfs = c.root.find("BRDFs")
    for b in (brdfs if brdfs is not None and bid else []):
        if b.get("id") == bid:
            if b.tag == "TorranceSparrow":
                return 1.0
            if b.tag in ("ModifiedPhong", "ModifiedBlinnPhong") and b.get("normalized", "").lower() == "true":
                return 1.0
    return math.pi


def value(c, name, rgb):
    """An rgb spectrum, or a raw 1x1 bitmap when a component is above 1."""
    rgb = [float(x) for x in rgb]
    if max(rgb) <= 1.0:
        return {"type": "rgb", "value": rgb}
    return {"type": "bitmap", "filename": c._constant_exr(name, rgb), "raw": True, "filter_type": "nearest"}


def _specular(c, mid, mat, kind, scale):
    """The specular child of mirror/conductor/dielectric materials (times scale), or None."""
    mirror = [scale * x for x in _nums(mat.find("MirrorReflectance"), [0, 0, 0])]
    n = _nums(mat.find("RefractionIndex"), [1.0])[0]
    if _nums(mat.find("Roughness"), [0])[0] > 0:
        c.warn("material %s: Roughness dropped (clrt's perturbation is no microfacet law)" % mid)
    if kind == "mirror":
        return {"type": "conductor", "material": "none", "specular_reflectance": value(c, "mr_" + mid, mirror)}
    if kind == "conductor":
        k = _nums(mat.find("AbsorptionIndex"), [0.0])[0]
        c.warn("material %s: conductor Fresnel exact in Mitsuba, the course's approximation in clrt" % mid)
        return {"type": "conductor", "eta": n, "k": k, "specular_reflectance": value(c, "mr_" + mid, mirror)}
    if kind == "dielectric" or mat.find("Transparency") is not None:
        absorb = _nums(mat.find("AbsorptionCoefficient"), [0, 0, 0])
        if mat.find("Transparency") is not None or max(absorb) > 0:
            c.warn("material %s: the dielectric's absorption dropped (path traces no media)" % mid)
        if scale != 1.0:
            c.warn("material %s: a dielectric with kd/ks: its half weight is not mapped" % mid)
        return {"type": "dielectric", "int_ior": n, "ext_ior": 1.0}
    return None


COURSE_BRDF_KINDS = {"originalphong": "original_phong", "originalblinnphong": "original_blinn_phong",
                     "modifiedphong": "modified_phong", "modifiedblinnphong": "modified_blinn_phong",
                     "torrancesparrow": "torrance_sparrow"}


def course_brdf(c, mat, kd, ks):
    """The plugin coursebrdf (bench/mitsuba_course_brdf.py) for a material with a specular lobe: its BRDF
    (Material BRDF="id"), or a classic material's Blinn-Phong (f = kd + ks cos^p αh / cosθi, p =
    PhongExponent: OriginalBlinnPhong)."""
    d = {"type": "coursebrdf", "kind": "original_blinn_phong",
         "exponent": _nums(mat.find("PhongExponent"), [1.0])[0]}
    bid = mat.get("BRDF")
    brdfs = c.root.find("BRDFs")
    for b in (brdfs if brdfs is not None and bid else []):
        if b.get("id") == bid:
            d["kind"] = COURSE_BRDF_KINDS[b.tag.lower()]
            d["exponent"] = _nums(b.find("Exponent"), [1.0])[0]
            d["normalized"] = b.get("normalized", "").strip().lower() in ("true", "1", "yes")
            d["kd_fresnel"] = b.get("kdfresnel", "").strip().lower() in ("true", "1", "yes")
    d["eta"] = _nums(mat.find("RefractionIndex"), [1.0])[0]
    d["k"] = _nums(mat.find("AbsorptionIndex"), [0.0])[0]
    for name, rgb in (("kd", kd), ("ks", ks)):
        for ch, x in zip("rgb", rgb):
            d["%s_%s" % (name, ch)] = float(x)
    return d


def textured_bsdf(c, mid, maps):
    """Mitsuba's BSDF of material mid on a shape with image maps (Converter._image_maps: replace_kd, blend_kd,
    replace_ks, texels linear after degamma and Normalizer): as bsdf(), its kd and ks from the maps."""
    return bsdf(c, mid, maps)


def _map_value(c, name, texels, filt):
    return {"type": "bitmap", "filename": c._texture_exr(name, texels), "raw": True, "filter_type": filt,
            "wrap_mode": "repeat"}


def bsdf(c, mid, maps=None):
    """Mitsuba's BSDF of material mid (see the module comment); maps: a textured shape's (textured_bsdf)."""
    mat = next((m for m in (c.root.find("Materials") or []) if m.get("id") == mid), None)
    if mat is None:
        c.warn("material %s not found: black" % mid)
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    kd = _nums(mat.find("DiffuseReflectance"), [0, 0, 0])
    ks = _nums(mat.find("SpecularReflectance"), [0, 0, 0])
    if mat.get("degamma", "").lower() == "true":
        kd, ks = [x ** 2.2 for x in kd], [x ** 2.2 for x in ks]
    kind = mat.get("type", "")
    nonspec = max(kd) > 0 or max(ks) > 0  # clrt's pick between the two parts (path.cl) counts ks too
    is_spec = kind in ("mirror", "conductor", "dielectric") or mat.find("Transparency") is not None
    w = 2.0 if (is_spec and nonspec) else 1.0  # each part picked with probability 1/2: blend of twice each
    kd_map = ks_map = None
    if maps:
        c.texture_count = getattr(c, "texture_count", 0) + 1
        n = "%s_%d" % (mid, c.texture_count)
        if "kd" in maps:
            mode, tex = maps["kd"]
            kd_map = tex if mode == "replace_kd" else 0.5 * (np.asarray(kd) + tex)  # blend_kd: the average
        if "ks" in maps:
            ks_map = maps["ks"][1]
        nonspec = nonspec or kd_map is not None or ks_map is not None
        w = 2.0 if (is_spec and nonspec) else 1.0
    if max(ks) > 0 or ks_map is not None:  # a specular lobe: the course's BRDF itself (mitsuba_course_brdf.py)
        diffuse = course_brdf(c, mat, [w * x for x in kd], [w * x for x in ks])
        if kd_map is not None:
            diffuse["kd_tex"] = _map_value(c, "kd_" + n, w * kd_map, maps["filter"])
        if ks_map is not None:
            diffuse["ks_tex"] = _map_value(c, "ks_" + n, w * ks_map, maps["filter"])
    elif kd_map is not None:
        diffuse = {"type": "diffuse", "reflectance": _map_value(c, "kd_" + n, w * diffuse_scale(c, mat) * kd_map, maps["filter"])}
    else:
        rho = [w * diffuse_scale(c, mat) * x for x in kd]
        diffuse = {"type": "diffuse", "reflectance": value(c, "kd_" + mid, rho)}
    spec = _specular(c, mid, mat, kind, w) if is_spec else None
    if spec is None:
        return {"type": "twosided", "bsdf": diffuse}
    if not nonspec:
        return spec if spec["type"] == "dielectric" else {"type": "twosided", "bsdf": spec}
    blend = {"type": "blendbsdf", "weight": 0.5, "a_diffuse": diffuse, "b_specular": spec}
    return blend if spec["type"] == "dielectric" else {"type": "twosided", "bsdf": blend}


# ---------------------------------------------------------------------------------------------- shapes
def _inline_mesh(c, el):
    """World-space (positions, faces) of an inline-faced (Light)Mesh."""
    faces_el = el.find("Faces")
    if faces_el.get("plyFile") or faces_el.get("binaryFile"):
        raise ValueError("%s %s: only inline faces are converted for object lights" % (el.tag, el.get("id")))
    idx = np.array(_nums(faces_el, []), dtype=np.int64).reshape(-1, 3)
    idx = idx + int(faces_el.get("vertexOffset", "0")) - (0 if c.zero_based else 1)
    used = np.unique(idx)
    remap = -np.ones(len(c.vertices), dtype=np.int64)
    remap[used] = np.arange(len(used))
    m = c.object_matrix(el)
    pos = c.vertices[used] @ m[:3, :3].T + m[:3, 3]
    return pos, remap[idx]


def _is_closed(faces):
    edges = {}
    for f in faces:
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            k = (min(a, b), max(a, b))
            edges[k] = edges.get(k, 0) + 1
    return all(v == 2 for v in edges.values())


def _emitting_faces(pos, faces, outward=False):
    """(positions, faces) whose front faces emit where clrt's two-sided light mesh does (outward: an open
    mesh too is only turned outwards; see the module comment)."""
    fn = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
    if outward or _is_closed(faces):  # turn each face away from the centroid
        out = (pos[faces].mean(axis=1) - pos.mean(axis=0)) * fn
        flip = out.sum(axis=1) < 0
        faces = faces.copy()
        faces[flip] = faces[flip][:, ::-1]
        return pos, faces
    eps = 1e-4 * float(np.linalg.norm(pos.max(0) - pos.min(0)))
    n = fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-30)
    tri = pos[faces]  # (F, 3, 3): one copy per side, offset along its own normal
    front = (tri + eps * n[:, None, :]).reshape(-1, 3)
    back = (tri - eps * n[:, None, :])[:, ::-1, :].reshape(-1, 3)
    allp = np.vstack([front, back])
    return allp, np.arange(len(allp)).reshape(-1, 3)


def _emitter(el):
    return {"type": "area", "radiance": {"type": "rgb", "value": _nums(el.find("Radiance"))}}


def shape(c, el, out):
    """LightMesh, LightSphere or MeshInstance el into out (Mitsuba shapes by name)."""
    mid = el.find("Material").text.strip() if el.find("Material") is not None else None
    if el.tag == "LightMesh":
        pos, faces = _inline_mesh(c, el)
        outward = getattr(c, "open_lights", "") == "outward"
        if outward and not _is_closed(faces):
            c.warn("LightMesh %s: open, turned outwards (open_lights=outward): its inner side must be closed off"
                   % el.get("id"))
        pos, faces = _emitting_faces(pos, faces, outward)
        path = c._write_ply("LightMesh_%s" % el.get("id"), pos, faces)
        out["lightmesh_" + el.get("id")] = {"type": "ply", "filename": path, "face_normals": True,
                                            "bsdf": c.bsdf(mid), "emitter": _emitter(el)}
    elif el.tag == "LightSphere":  # an ellipsoid: a mesh (Converter.sphere_shape)
        d = c.sphere_shape(el, "LightSphere_" + el.get("id"), {"emitter": _emitter(el)})
        if d["type"] != "sphere":
            c.warn("LightSphere %s: an ellipsoid lights the scene in clrt as the course's renderer does (its object-space "
                   "sphere's light, docs/scene-format.md), in Mitsuba with a constant radiance over its surface: the "
                   "means disagree" % el.get("id"))
        out["lightsphere_" + el.get("id")] = d
    else:
        _instance(c, el, mid, out)


def _instance(c, el, mid, out):
    """A MeshInstance of a Mesh: the base's geometry, its own material and transformation (after the
    base's unless resetTransform)."""
    base = next((m for m in c.root.find("Objects") if m.tag == "Mesh" and m.get("id") == el.get("baseMeshId")), None)
    if base is None:
        c.warn("MeshInstance %s: base %s is no Mesh: dropped" % (el.get("id"), el.get("baseMeshId")))
        return
    tmp = {}
    c._mesh(base, tmp, "Mesh")
    if not tmp:
        return
    d = dict(next(iter(tmp.values())))
    own = c.object_matrix(el)
    d["to_world"] = (own if el.get("resetTransform", "").lower() == "true" else own @ c.object_matrix(base)).tolist()
    d["bsdf"] = c.bsdf(mid or base.find("Material").text.strip())
    if el.find("Textures") is not None:
        c.warn("MeshInstance %s: textures dropped" % el.get("id"))
    out["instance_" + el.get("id")] = d


def area_light(c, el):
    """clrt's two-sided AreaLight square: two Mitsuba rectangles back to back (see the module comment)."""
    p, n = np.array(_nums(el.find("Position"))), np.array(_nums(el.find("Normal")))
    size = float(el.find("Size").text)
    n = n / np.linalg.norm(n)
    a = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    if el.find("Transformations") is not None:
        c.warn("AreaLight %s: Transformations ignored" % el.get("id"))
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    out = {}
    for side, sgn in (("front", 1.0), ("back", -1.0)):
        m = np.eye(4)  # rectangle: [-1,1]^2 in xy, normal +z; the back copy mirrored so that it faces -n
        m[:3, 0], m[:3, 1], m[:3, 2] = a * size / 2, sgn * b * size / 2, sgn * n
        m[:3, 3] = p + sgn * 1e-4 * size * n
        out["area_%s_%s" % (el.get("id", "0"), side)] = {"type": "rectangle", "to_world": m.tolist(), "bsdf": black,
                                                         "emitter": _emitter(el)}
    c.warn("AreaLight %s: two back-to-back rectangles (they occlude and are visible in Mitsuba; clrt's is not geometry)"
           % el.get("id"))
    return out
