#!/usr/bin/env python3
"""to_mitsuba.py — converts a CENG795 XML scene (SCENE_FORMAT.md) into a Mitsuba 3 scene dict, for the
benchmark (bench/bench.py --mitsuba) and for a reader who wants to check clrt against another renderer.

Reads: the first camera (lookAt or simple; FovY/NearPlane, ImageResolution), VertexData, Mesh (PLY or
inline Faces; Transformations; shadingMode), Triangle, Sphere (Center, Radius, Transformations), the
Materials' DiffuseReflectance, Point/Directional/Area lights and SphericalDirectionalLight (lat-long,
and probe maps resampled to lat-long). Drops, with a warning each: specular/mirror/dielectric/conductor
terms, textures, spot and ambient lights, MeshInstance, LightMesh/LightSphere, degamma, thin lens.
With path_tracing=True (bench/bench_mitsuba_path.py) it also converts what a path-traced course scene
needs (to_mitsuba_path.py: mirrors, dielectrics, conductors, BRDF diffuse scaling, LightMesh,
LightSphere, two-sided AreaLights, MeshInstance, the depth and roulette settings) and the image textures
of inline meshes with TexCoordData (replace_kd, blend_kd, replace_ks: Converter._image_maps).

Conventions (measured against clrt, see bench/README.md "Against Mitsuba 3"):
- Radiance: the course's shading model has no 1/π in the diffuse term (L = kd·cosθ·E); Mitsuba's
  Lambertian BRDF is ρ/π. So every diffuse reflectance is converted to ρ = π·kd and the emitters keep
  their values: one Mitsuba render is the course's image, the environment seen by the camera included
  (the same work per sample as clrt's). Mitsuba refuses an `rgb` reflectance above 1, so a ρ above 1
  (any kd > 1/π) is a 1×1 raw `bitmap` texture instead (nearest lookup), written beside the PLY files.
  (Until 2026-11-30 the emitters were scaled by π, the camera was blind to them and the camera-visible
  environment was rendered once at high spp and added: that kept the background's work and noise out
  of Mitsuba's timed render. The benchmarks' caches of Mitsuba references are keyed by code_hash(): a
  reference converted by other code is rendered again.)
- Direct lighting only (clrt's renderer has no diffuse inter-reflection): path max_depth 2.
- Environment orientation: clrt's lat-long u = (1 + atan2(dx, −dz)/π)/2 puts −z at u = ½; Mitsuba's
  envmap puts −z at u = 0, so the map is turned 180° about y.
- Camera: Mitsuba's look_at with fov_axis y is the course's right-handed camera (gaze × up to the right);
  handedness="left" is flipped with a negative x scale. Pixel filter: box (as clrt), sampler independent.
"""
import math
import os
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

CONVERTER_FILES = ("to_mitsuba.py", "to_mitsuba_path.py", "mitsuba_course_brdf.py")  # what a conversion runs


def code_hash():
    """The first 8 hex digits of a sha256 of the conversion's code (CONVERTER_FILES, beside this file): part of the
    key of every cached Mitsuba reference (bench.py, bench_mitsuba_path.py), so none converted by older code is used."""
    import hashlib
    h = hashlib.sha256()
    here = os.path.dirname(os.path.abspath(__file__))
    for f in CONVERTER_FILES:
        with open(os.path.join(here, f), "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()[:8]


def _nums(el, default=None):
    if el is None or el.text is None or not el.text.strip():
        return default
    return [float(x) for x in el.text.split()]


def _mat_mul(a, b):
    return (np.asarray(a) @ np.asarray(b)).tolist()


class Converter:
    def __init__(self, path, warn=None, path_tracing=False, open_lights="two-sided"):
        self.path_tracing = path_tracing
        if open_lights not in ("two-sided", "outward"):
            raise ValueError("open_lights: two-sided or outward, not %r" % (open_lights,))
        self.open_lights = open_lights  # an open LightMesh: "two-sided" or "outward" (to_mitsuba_path.py)
        self.path = os.path.abspath(path)
        self.base = os.path.dirname(self.path)
        self.root = ET.parse(self.path).getroot()
        self.warnings = []
        self._warn_fn = warn
        self.tmp = tempfile.mkdtemp(prefix="clrt-mitsuba-")
        self.vertices = np.zeros((0, 3))
        vd = self.root.find("VertexData")
        if vd is not None:
            if vd.get("binaryFile"):
                self.warn("VertexData binaryFile not supported: dropped")
            else:
                self.vertices = np.array(_nums(vd, []), dtype=np.float64).reshape(-1, 3)
        tc = self.root.find("TexCoordData")
        self.uvs = None  # per vertex (the VertexData's indexing), course convention: v grows downwards
        if tc is not None and not tc.get("binaryFile"):
            self.uvs = np.array(_nums(tc, []), dtype=np.float64).reshape(-1, 2)
        zb = self.root.find("ZeroBasedIndexing")
        self.zero_based = zb is not None and zb.text.strip().lower() == "true"
        self.transforms = self._read_transforms()
        self.materials = {}
        self.images = {}
        for img in self.root.iter("Image"):
            p = img.text.strip()
            self.images[img.get("id")] = p if os.path.isabs(p) else os.path.normpath(os.path.join(self.base, p))

    def warn(self, msg):
        if msg in self.warnings:
            return
        self.warnings.append(msg)
        if self._warn_fn:
            self._warn_fn("to_mitsuba: " + msg)

    def _abs(self, p):
        return p if os.path.isabs(p) else os.path.normpath(os.path.join(self.base, p))

    # ------------------------------------------------------------------------------- transformations
    def _read_transforms(self):
        t = {}
        tr = self.root.find("Transformations")
        if tr is None:
            return t
        for el in tr:
            v = _nums(el, [])
            i = el.get("id")
            if el.tag == "Translation":
                m = np.eye(4)
                m[:3, 3] = v[:3]
                t["t" + i] = m
            elif el.tag == "Scaling":
                t["s" + i] = np.diag([v[0], v[1], v[2], 1.0])
            elif el.tag == "Rotation":
                a = math.radians(v[0])
                ax = np.array(v[1:4]) / np.linalg.norm(v[1:4])
                x, y, z = ax
                c, s, C = math.cos(a), math.sin(a), 1 - math.cos(a)
                m = np.eye(4)
                m[:3, :3] = [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                             [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                             [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]
                t["r" + i] = m
            elif el.tag == "Composite":
                t["c" + i] = np.array(v, dtype=np.float64).reshape(4, 4)
        return t

    def object_matrix(self, el):
        """"t1 s2" means first t1, then s2: M = S2·T1."""
        m = np.eye(4)
        tr = el.find("Transformations")
        if tr is not None and tr.text:
            for ref in tr.text.split():
                if ref not in self.transforms:
                    self.warn("unknown transformation %s: ignored" % ref)
                    continue
                m = self.transforms[ref] @ m
        return m

    # ------------------------------------------------------------------------------------ materials
    def bsdf(self, mid):
        if mid in self.materials:
            return self.materials[mid]
        if self.path_tracing:
            import to_mitsuba_path
            self.materials[mid] = to_mitsuba_path.bsdf(self, mid)
            return self.materials[mid]
        mat = None
        mats = self.root.find("Materials")
        for m in (mats if mats is not None else []):
            if m.get("id") == mid:
                mat = m
        kd = [0.0, 0.0, 0.0]
        if mat is not None:
            kd = _nums(mat.find("DiffuseReflectance"), kd)
            kind = mat.get("type", "")
            if kind:
                self.warn("material %s type=%s: only its diffuse term is kept" % (mid, kind))
            ks = _nums(mat.find("SpecularReflectance"), [0, 0, 0])
            if max(ks) > 0:
                self.warn("material %s: SpecularReflectance dropped (diffuse only)" % mid)
            if mat.get("degamma", "").lower() == "true":
                self.warn("material %s: degamma ignored" % mid)
            if mat.get("BRDF"):
                self.warn("material %s: BRDF %s replaced by Lambert" % (mid, mat.get("BRDF")))
        rho = [math.pi * x for x in kd]  # the course's kd·cosθ·E = Mitsuba's (ρ/π)·cosθ·E
        if max(rho) <= 1.0:
            refl = {"type": "rgb", "value": rho}
        else:  # Mitsuba's rgb reflectance refuses values above 1; a raw bitmap takes them
            refl = {"type": "bitmap", "filename": self._constant_exr("kd_" + mid, rho), "raw": True,
                    "filter_type": "nearest"}
        b = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}
        self.materials[mid] = b
        return b

    def _texture_exr(self, name, texels):
        """An H×W float EXR of texels (row 0 at the top): a texture Mitsuba reads as it is (raw)."""
        import OpenEXR as E
        path = os.path.join(self.tmp, name + ".exr")
        E.File({"compression": E.ZIP_COMPRESSION}, {"RGB": np.ascontiguousarray(texels, dtype=np.float32)}).write(path)
        return path

    def _constant_exr(self, name, rgb):
        """A 1x1 float EXR of the value rgb (a texture that Mitsuba does not clamp)."""
        import OpenEXR as E
        path = os.path.join(self.tmp, name + ".exr")
        E.File({"compression": E.ZIP_COMPRESSION}, {"RGB": np.array([[rgb]], dtype=np.float32)}).write(path)
        return path

    # ------------------------------------------------------------------------------------- geometry
    def _write_ply(self, name, pos, faces, normals=None, uv=None):
        path = os.path.join(self.tmp, name + ".ply")
        n = len(pos)
        with open(path, "wb") as f:
            hdr = "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n" % n
            if normals is not None:
                hdr += "property float nx\nproperty float ny\nproperty float nz\n"
            if uv is not None:
                hdr += "property float u\nproperty float v\n"
            hdr += "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(faces)
            f.write(hdr.encode())
            cols = [pos] + ([normals] if normals is not None else []) + ([uv] if uv is not None else [])
            v = np.hstack(cols).astype("<f4")
            f.write(v.tobytes())
            fa = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
            fa["n"] = 3
            fa["i"] = faces
            f.write(fa.tobytes())
        return path

    def sphere_shape(self, el, name, extra=None):
        """Sphere or LightSphere el as a Mitsuba shape: a `sphere` under a similarity, else (an ellipsoid, which
        Mitsuba's sphere cannot be) a UV sphere of 128 x 64 quads with the ellipsoid's own vertex normals, its
        faces turned outwards (the emitting side of a LightSphere). Its area is within 0.02% of the ellipsoid's."""
        ci = int(el.find("Center").text) - (0 if self.zero_based else 1)
        c = np.array(self.vertices[ci], dtype=float)
        r = float(el.find("Radius").text)
        m = self.object_matrix(el)
        d = dict(extra or {}, bsdf=self.bsdf(el.find("Material").text.strip()))
        sv = np.linalg.svd(m[:3, :3], compute_uv=False)
        if sv.max() - sv.min() <= 1e-6 * sv.max():
            world = m @ np.array([[r, 0, 0, c[0]], [0, r, 0, c[1]], [0, 0, r, c[2]], [0, 0, 0, 1.0]])
            return dict(d, type="sphere", to_world=world.tolist())
        nu, nv = 128, 64
        th = np.linspace(0.0, math.pi, nv + 1)[:, None]
        ph = np.linspace(0.0, 2.0 * math.pi, nu + 1)[None, :]
        unit = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th) * np.ones_like(ph)], -1).reshape(-1, 3)
        pos = (c + r * unit) @ m[:3, :3].T + m[:3, 3]
        nrm = unit @ np.linalg.inv(m[:3, :3])  # normals by the inverse transpose
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        i = np.arange(nv)[:, None] * (nu + 1) + np.arange(nu)[None, :]
        quads = np.stack([i, i + nu + 1, i + nu + 2, i + 1], -1).reshape(-1, 4)
        faces = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        if np.linalg.det(m[:3, :3]) < 0:
            faces = faces[:, ::-1]
        a, b, cc = pos[faces[:, 0]], pos[faces[:, 1]], pos[faces[:, 2]]
        faces = faces[np.linalg.norm(np.cross(b - a, cc - a), axis=1) > 0]  # the poles' empty triangles
        self.warn("%s %s: an ellipsoid (not a similarity): a mesh of %d triangles in Mitsuba" % (el.tag, el.get("id"), len(faces)))
        return dict(d, type="ply", filename=self._write_ply(name, pos, faces, nrm))

    def _mesh(self, el, shapes, kind):
        mid = el.find("Material").text.strip()
        m = self.object_matrix(el)
        smooth = el.get("shadingMode", "flat") == "smooth"
        faces_el = el.find("Faces") if kind == "Mesh" else el.find("Indices")
        textured = None  # path tracing: the image maps this mesh's material takes (to_mitsuba_path.textured_bsdf)
        if el.find("Textures") is not None:
            textured = self._image_maps(el, kind) if self.path_tracing and not faces_el.get("plyFile") else None
            if not textured:
                self.warn("%s %s: textures dropped" % (kind, el.get("id")))
        d = {"bsdf": self.bsdf(mid), "to_world": m.tolist()}
        if textured:
            import to_mitsuba_path
            d["bsdf"] = to_mitsuba_path.textured_bsdf(self, mid, textured)
        if kind == "Mesh" and faces_el.get("plyFile"):
            d.update(type="ply", filename=self._abs(faces_el.get("plyFile")), face_normals=not smooth)
        else:
            if faces_el.get("binaryFile"):
                self.warn("%s %s: binary faces not supported: dropped" % (kind, el.get("id")))
                return
            idx = np.array(_nums(faces_el, []), dtype=np.int64).reshape(-1, 3)
            off = int(faces_el.get("vertexOffset", "0"))
            idx = idx + off - (0 if self.zero_based else 1)
            used = np.unique(idx)
            remap = -np.ones(len(self.vertices), dtype=np.int64)
            remap[used] = np.arange(len(used))
            pos, faces = self.vertices[used], remap[idx]
            normals = None
            if smooth:  # area-weighted vertex normals, as clrt computes them
                fn = np.cross(pos[faces[:, 1]] - pos[faces[:, 0]], pos[faces[:, 2]] - pos[faces[:, 0]])
                normals = np.zeros_like(pos)
                for k in range(3):
                    np.add.at(normals, faces[:, k], fn)
                normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
            uv = None
            if textured:  # clrt's bilinear lookup (textures.cl) has texel corners at integer u·w, Mitsuba's centres;
                # v as the course's (row 0 at the top, v down): Mitsuba's bitmap reads it so (checked: hw4's wood box)
                w, h = textured["size"]
                shift = 0.5 if textured["filter"] == "bilinear" else 0.0
                uv = self.uvs[used] + np.array([shift / w, shift / h])
            path = self._write_ply("%s_%s" % (kind, el.get("id")), pos, faces, normals, uv)
            d.update(type="ply", filename=path, face_normals=not smooth)
        shapes["%s_%s" % (kind.lower(), el.get("id"))] = d

    def _image_maps(self, el, kind):
        """The image TextureMaps of shape el that the path converter maps (replace_kd, blend_kd, replace_ks) as
        {"kd": (mode, texels), "ks": ..., "size": (w, h), "filter": ...}: texels linear, after degamma and the
        Normalizer, as clrt's flatten_textures.cpp makes them; None (the caller warns) for anything else."""
        if self.uvs is None:
            return None
        maps = {t.get("id"): t for t in self.root.iter("TextureMap")}
        out = {}
        for tid in el.find("Textures").text.split():
            t = maps.get(tid)
            mode = (t.findtext("DecalMode") or "").strip() if t is not None else ""
            if t is None or t.get("type") != "image" or mode not in ("replace_kd", "blend_kd", "replace_ks"):
                self.warn("%s %s: TextureMap %s (%s) not mapped" % (kind, el.get("id"), tid,
                                                                   "missing" if t is None else t.get("type", "") + " " + mode))
                return None
            path = self.images[t.findtext("ImageId").strip()]
            hdr = path.lower().endswith((".exr", ".hdr"))
            if hdr:
                import OpenEXR as E
                with E.File(path) as f:
                    img = np.asarray(next(iter(f.parts[0].channels.values())).pixels, dtype=np.float64)
            else:
                from PIL import Image as PILImage
                img = np.asarray(PILImage.open(path).convert("RGB"), dtype=np.float64)
            img = img[..., :3]
            rng = 1.0 if hdr else 255.0
            if t.get("degamma", "").strip().lower() in ("true", "1", "yes"):
                img = np.where(img > 0, rng * (img / rng) ** 2.2, 0.0)
            norm = float(t.findtext("Normalizer")) if t.find("Normalizer") is not None else rng
            interp = (t.findtext("Interpolation") or "nearest").strip()
            if interp == "trilinear":
                self.warn("TextureMap %s: trilinear (mip-maps) mapped as bilinear" % tid)
            filt = "nearest" if interp == "nearest" else "bilinear"
            if "filter" in out and out["filter"] != filt or "size" in out and out["size"] != (img.shape[1], img.shape[0]):
                self.warn("%s %s: texture maps of different sizes or filters" % (kind, el.get("id")))
                return None
            out["filter"], out["size"] = filt, (img.shape[1], img.shape[0])
            out["ks" if mode == "replace_ks" else "kd"] = (mode, img / norm)
        return out

    def shapes(self):
        out = {}
        objs = self.root.find("Objects")
        for el in (objs if objs is not None else []):
            if el.tag in ("Mesh", "Triangle"):
                self._mesh(el, out, el.tag)
            elif el.tag == "Sphere":
                if el.find("Textures") is not None:
                    self.warn("Sphere %s: textures dropped" % el.get("id"))
                out["sphere_" + el.get("id")] = self.sphere_shape(el, "Sphere_" + el.get("id"))
            elif self.path_tracing and el.tag in ("LightMesh", "LightSphere", "MeshInstance"):
                import to_mitsuba_path
                to_mitsuba_path.shape(self, el, out)
            else:
                self.warn("%s dropped (not converted)" % el.tag)
        return out

    # ---------------------------------------------------------------------------------------- lights
    def _latlong_from_probe(self, path):
        """Resamples an angular (probe) map to a 2:1 lat-long one in clrt's lat-long convention."""
        import OpenEXR
        with OpenEXR.File(path) as f:
            ch = f.channels()
            img = ch["RGB"].pixels if "RGB" in ch else ch["RGBA"].pixels[..., :3]
        img = np.asarray(img, dtype=np.float32)
        h, w = img.shape[:2]
        H = max(16, h)
        W = 2 * H
        u = (np.arange(W) + 0.5) / W
        v = (np.arange(H) + 0.5) / H
        uu, vv = np.meshgrid(u, v)
        phi, theta = math.pi * (2 * uu - 1), math.pi * vv
        dx, dy, dz = np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)
        s = np.sqrt(dx * dx + dy * dy)
        R = np.arctan2(s, -dz) / math.pi
        x = np.where(s > 0, R * dx / np.maximum(s, 1e-30), R)
        y = np.where(s > 0, R * dy / np.maximum(s, 1e-30), 0.0)
        pu, pv = 0.5 * (x + 1) * w - 0.5, 0.5 * (1 - y) * h - 0.5
        x0, y0 = np.floor(pu).astype(int), np.floor(pv).astype(int)
        fx, fy = (pu - x0)[..., None], (pv - y0)[..., None]
        cl = lambda a, n: np.clip(a, 0, n - 1)
        t = lambda yy, xx: img[cl(yy, h), cl(xx, w)]
        out = (t(y0, x0) * (1 - fx) * (1 - fy) + t(y0, x0 + 1) * fx * (1 - fy) + t(y0 + 1, x0) * (1 - fx) * fy
               + t(y0 + 1, x0 + 1) * fx * fy)
        p = os.path.join(self.tmp, "probe_latlong.exr")
        import OpenEXR as E
        E.File({"compression": E.ZIP_COMPRESSION}, {"RGB": np.ascontiguousarray(out.astype(np.float32))}).write(p)
        return p

    def env(self):
        """(filename, mapping) of the scene's environment light, or None."""
        lights = self.root.find("Lights")
        for el in (lights if lights is not None else []):
            if el.tag == "SphericalDirectionalLight":
                path = self.images.get(el.find("ImageId").text.strip())
                if el.get("type", "latlong") == "probe":
                    path = self._latlong_from_probe(path)
                return path
        return None

    def emitters(self):
        out = {}
        lights = self.root.find("Lights")
        for el in (lights if lights is not None else []):
            lid = el.get("id", "0")
            if el.tag == "PointLight":
                out["point_" + lid] = {"type": "point", "position": _nums(el.find("Position")),
                                       "intensity": {"type": "rgb", "value": _nums(el.find("Intensity"))}}
            elif el.tag == "DirectionalLight":
                out["dir_" + lid] = {"type": "directional", "direction": _nums(el.find("Direction")),
                                     "irradiance": {"type": "rgb", "value": _nums(el.find("Radiance"))}}
            elif el.tag == "AreaLight" and self.path_tracing:
                import to_mitsuba_path
                out.update(to_mitsuba_path.area_light(self, el))
            elif el.tag == "AreaLight":
                p, n, size = np.array(_nums(el.find("Position"))), np.array(_nums(el.find("Normal"))), float(el.find("Size").text)
                n = n / np.linalg.norm(n)
                a = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
                a /= np.linalg.norm(a)
                b = np.cross(n, a)
                m = np.eye(4)
                m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = a * size / 2, b * size / 2, n, p
                self.warn("AreaLight %s: a rectangle in Mitsuba (it occludes and the camera sees it; clrt's does neither)" % lid)
                out["area_" + lid] = {"type": "rectangle", "to_world": m.tolist(),
                                      "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}},
                                      "emitter": {"type": "area", "radiance": {"type": "rgb", "value": _nums(el.find("Radiance"))}}}
            elif el.tag == "SphericalDirectionalLight":
                path = self.env()
                out["env_" + lid] = {"type": "envmap", "filename": path,
                                     "to_world": [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, 1]]}
            elif el.tag == "AmbientLight":
                if max(_nums(el, [0])) > 0:
                    self.warn("AmbientLight dropped")
            else:
                self.warn("%s dropped (not converted)" % el.tag)
        return out

    # ---------------------------------------------------------------------------------------- camera
    def sensor(self, spp, res=None):
        cam = self.root.find("Cameras")[0]
        pos = np.array(_nums(cam.find("Position")))
        up = np.array(_nums(cam.find("Up")))
        w, h = (int(x) for x in cam.find("ImageResolution").text.split())
        if res:
            w, h = res
        if cam.get("type") == "lookAt":
            gp = cam.find("GazePoint")
            gaze = np.array(_nums(gp)) - pos if gp is not None else np.array(_nums(cam.find("Gaze")))
            fovy = float(cam.find("FovY").text)
        else:
            gaze = np.array(_nums(cam.find("Gaze")))
            l, r, b, t = _nums(cam.find("NearPlane"))
            nd = float(cam.find("NearDistance").text)
            if abs(l + r) > 1e-6 * abs(r - l) or abs(b + t) > 1e-6 * abs(t - b):
                self.warn("off-centre NearPlane: converted as a centred one")
            fovy = math.degrees(2 * math.atan(0.5 * (t - b) / nd))
        if cam.find("ApertureSize") is not None:
            self.warn("thin lens dropped (pinhole)")
        m = _look_at(pos, pos + gaze, up)
        if cam.get("handedness") == "left":
            m = _mat_mul(m, np.diag([-1.0, 1, 1, 1]))
        return {"type": "perspective", "fov_axis": "y", "fov": fovy, "to_world": m,
                "near_clip": 1e-3, "far_clip": 1e7,
                "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                "sampler": {"type": "independent", "sample_count": spp}}


def _look_at(origin, target, up):
    """Mitsuba's look_at (camera looks along +z, +x to the left, +y up), as a plain matrix."""
    d = target - origin
    d = d / np.linalg.norm(d)
    left = np.cross(up, d)
    left /= np.linalg.norm(left)
    nu = np.cross(d, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, nu, d, origin
    return m.tolist()


def scene_dict(path, spp, res=None, warn=None, path_tracing=False, open_lights="two-sided"):
    """(scene, warnings): the Mitsuba scene dict whose image is the course's image of the scene's first
    camera (see the module's comment). path_tracing: the camera's path tracer (to_mitsuba_path.py);
    open_lights: how it converts an open LightMesh ("two-sided" or "outward", to_mitsuba_path.py)."""
    c = Converter(path, warn, path_tracing, open_lights)
    integrator = {"type": "path", "max_depth": 2}
    if path_tracing:
        import to_mitsuba_path
        integrator = to_mitsuba_path.integrator(c)
    scene = {"type": "scene", "integrator": integrator, "sensor": c.sensor(spp, res)}
    scene.update(c.shapes())
    scene.update(c.emitters())
    return scene, c.warnings


def materialize(d, mi):
    """The dict with Mitsuba types where load_dict needs them (to_world matrices, points, vectors)."""
    if isinstance(d, dict):
        out = {}
        for k, v in d.items():
            if k == "to_world":
                out[k] = mi.ScalarTransform4f(np.asarray(v, dtype=np.float64).tolist())
            elif k in ("position", "direction") and isinstance(v, list):
                out[k] = mi.ScalarPoint3f(*v) if k == "position" else mi.ScalarVector3f(*v)
            else:
                out[k] = materialize(v, mi)
        return out
    return d


if __name__ == "__main__":
    import pprint
    s, w = scene_dict(sys.argv[1], 4, warn=lambda m: print(m, file=sys.stderr))
    pprint.pprint({k: v for k, v in s.items() if not k.startswith(("mesh_", "triangle_"))})
