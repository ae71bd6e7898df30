"""bench_mitsuba_path.py — clrt's path tracer against Mitsuba 3's `path` integrator (issue 32), called by
bench.py --mitsuba-path (scripts/bench --mitsuba-path). Reads the scenes below from ../shared (copies made
at run time, nothing of them committed) and converts them with to_mitsuba.py (path_tracing=True,
to_mitsuba_path.py).

Scenes (all with clrt's MultipleImportanceSampling, no Russian roulette on either side, box filter):
- hw6_box: the hw6 path box (cornellbox_jaroslav_path_diffuse.xml, camera 1's view, bench_path.py's
  copy: PointLight removed) at the course's MaxRecursionDepth 3.
  Its light box is open at the top, where the ceiling closes it: converted with open_lights="outward"
  (to_mitsuba_path.py), one copy of its faces turned outwards, the area clrt samples.
- hw6_glass_box: the same with the yellow sphere glass (scripts/path_glass_box.sh), depth 3 as the
  course's glass box; the glass's Phong lobe (SpecularReflectance 0.3) and absorption (0.01) zeroed on
  both sides (no Mitsuba equivalent: to_mitsuba_path.py).
- veach_ajar: classic/veachAjar.xml's geometry lit as the course's hw6 veach-ajar scene (one AreaLight
  behind the door, Radiance 1000, Normal (0 -1 1), Size 3; MaxRecursionDepth 6), with hw6's materials
  less what does not map: textures and specular lobes dropped, the pots' glass without absorption; the
  mirror-and-diffuse materials (floor, handles, table legs, one pot) kept (a Mitsuba blendbsdf).
Per scene: a reference of each renderer (two independent halves, cached under --refs), the per-channel
means of the two references (must agree within 1%), then --runs runs at each spp: clrt's render-stage
time, process wall and CPU time (getrusage of the child), Mitsuba's mi.render wall and process CPU time
(time.process_time), both on the same thread count; relMSE of each against its own reference;
efficiency = 1/(relMSE x time); ratio clrt/Mitsuba = time factor x noise factor.
--depth-check: the box at clrt depths 0 and 1 against Mitsuba max_depth d+1 and d+2 (the mapping's test).
--scene-file FILE[@CAMERA],...: any course scene (XML, or 2025 JSON: json_to_xml) instead of the three above (user_scene below): one of
its cameras (the first unless @N, 1-based), its own depth and RendererParams (or --path-params; Russian
roulette removed, as above; a camera that is not path traced is made so, with MultipleImportanceSampling; one
whose strategy has no next-event estimation, unlike `path`, is rendered so and noted), the resolution scaled to --path-res on the long side, references of --path-ref-spp; what the
conversion cannot map is listed under the report's table ("Conversion warnings"), and the means must still
agree within 1% for the efficiency to count.
Writes mitsuba_path.csv, mitsuba_path_runs.csv, mitsuba_path_<scene>.png, mitsuba_path_report.md."""
import json
import os
import re
import resource
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np

import bench_path
import to_mitsuba
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
from scene_json import json_to_element  # noqa: E402  (scripts/scene_json.py, shared with check_course.py)

ROOT = bench_path.ROOT
SHARED = os.environ.get("CLRT_SHARED_SCENES", bench_path.SHARED)  # ../shared/scenes beside the checkout
BOX = os.path.join(SHARED, "hw6", "cornellbox_jaroslav_path_diffuse.xml")
VEACH = os.path.join(SHARED, "classic", "veachAjar.xml")
SCENES = [
    dict(name="hw6_box", path=BOX, res=(128, 128), depth=3, glass=False, ref_spp=2048, open_lights="outward"),
    dict(name="hw6_glass_box", path=BOX, res=(128, 128), depth=3, glass=True, ref_spp=2048, open_lights="outward"),
    dict(name="veach_ajar", path=VEACH, res=(128, 90), depth=6, ref_spp=1024),
]
SPP = [16, 64, 256]
MI_PASS = 64  # Mitsuba's references in passes of this many spp
VEACH_LIGHTS = ('<Lights><AreaLight id="1"><Position>-4.4391 1.50656 -4.44377</Position><Normal>0 -1 1</Normal>'
                '<Size>3</Size><Radiance>1000 1000 1000</Radiance></AreaLight></Lights>')
# hw6 veach-ajar's materials (BRDF 1: normalized ModifiedPhong) less textures, specular lobes, absorption
VEACH_MATERIALS = [("1", "", "1 1 1", ""), ("2", "", "0.8 0.8 0.8", ""), ("3", "dielectric", "0 0 0", "1.5"),
                   ("4", "mirror", "0.2 0.2 0.2", "0.3"), ("5", "mirror", "0.6 0.6 0.6", "0.4"),
                   ("6", "", "0.8 0.8 0.8", ""), ("7", "", "1 0.8 0.58", ""), ("8", "", "1 0.64 0.36", ""),
                   ("9", "mirror", "0.2 0.2 0.2", "0.3"), ("10", "mirror", "0.8 0.8 0.8", "0.04")]


def _material(mid, kind, kd, x):
    extra = ""
    if kind == "mirror":
        extra = "<MirrorReflectance>%s %s %s</MirrorReflectance>" % (x, x, x)
    elif kind == "dielectric":
        extra = "<RefractionIndex>%s</RefractionIndex>" % x
    return ('<Material id="%s" BRDF="1"%s><DiffuseReflectance>%s</DiffuseReflectance><SpecularReflectance>0 0 0'
            '</SpecularReflectance>%s</Material>' % (mid, ' type="%s"' % kind if kind else "", kd, extra))


def veach_square():
    """The corners of hw6's AreaLight square as clrt places it (flatten_lights.cpp: u = cross(helper, n),
    v = cross(n, u), helper x unless |n.x| > 0.9)."""
    p, n, size = np.array([-4.4391, 1.50656, -4.44377]), np.array([0.0, -1.0, 1.0]) / np.sqrt(2.0), 3.0
    u = np.cross([1.0, 0, 0], n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    return np.array([p + 0.5 * size * (su * u + sv * v) for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


VEACH_LIGHT_MESH = ('<LightMesh id="1"><Material>11</Material><Radiance>1000 1000 1000</Radiance>'
                    '<Faces vertexOffset="1">0 1 2 0 2 3</Faces></LightMesh>')


def veach_scene(sc, depth, tmpdir, params, area_light=False):
    """classic/veachAjar.xml as described in the module comment; PLY paths made absolute."""
    s = open(sc["path"]).read()
    base = os.path.dirname(sc["path"])
    s = re.sub(r'plyFile="([^"]+)"', lambda m: 'plyFile="%s"' % os.path.join(base, m.group(1)), s)
    s = re.sub(r"<MaxRecursionDepth>\d+</MaxRecursionDepth>", "<MaxRecursionDepth>%d</MaxRecursionDepth>" % depth, s)
    s = re.sub(r"<Lights>.*?</Lights>", VEACH_LIGHTS if area_light else "", s, flags=re.S)
    if not area_light:  # the same square as a LightMesh: geometry in both renderers (module comment)
        s = s.replace("<Objects>", "<VertexData>%s</VertexData>\n<Objects>\n%s" % (
            " ".join("%.6f" % x for x in veach_square().ravel()), VEACH_LIGHT_MESH), 1)
        assert "<VertexData>" in s and s.count("<VertexData>") == 1
    mats = "\n".join(_material(*m) for m in VEACH_MATERIALS + [("11", "", "0 0 0", "")])
    s = re.sub(r"<Materials>.*?</Materials>", '<BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>90</Exponent>'
               '</ModifiedPhong></BRDFs>\n<Materials>\n' + mats + '\n</Materials>', s, flags=re.S)
    s = re.sub(r"<Textures>.*?</Textures>", "", s, flags=re.S)  # the texture section and each object's refs
    cam = ("<ImageName>img.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>%s</RendererParams>"
           % params)
    s = re.sub(r"<ImageName>.*?</ImageName>", cam, s)
    s = re.sub(r"<ImageResolution>.*?</ImageResolution>", "<ImageResolution>%d %d</ImageResolution>" % sc["res"], s)
    s = re.sub(r"<NumSamples>.*?</NumSamples>", "", s)
    out = os.path.join(tmpdir, "%s-d%d%s.xml" % (sc["name"], depth, "-area" if area_light else ""))
    open(out, "w").write(s)
    return out


def json_to_xml(path):
    """A scene in the 2025 JSON form as the XML tree it transliterates (scripts/scene_json.py: the rule clrt's
    reader follows)."""
    with open(path) as f:
        doc = json.load(f)
    if not isinstance(doc, dict) or "Scene" not in doc:
        raise SystemExit("bench: --scene-file %s: no \"Scene\" at the top of the JSON" % path)
    return ET.ElementTree(json_to_element("Scene", doc["Scene"]))


def parse_scene(path):
    """The scene file as an XML tree: XML as it is, the 2025 JSON form transliterated (json_to_xml)."""
    with open(path, "rb") as f:
        head = f.read(64).lstrip(b"\xef\xbb\xbf \t\r\n")
    return json_to_xml(path) if head.startswith(b"{") else ET.parse(path)


def user_scene(spec, long_side, ref_spp):
    """A SCENES entry for --scene-file FILE[@CAMERA]: the camera (1-based, default the first), its resolution
    scaled to long_side on the long side (aspect kept), its depth as clrt reads it (the camera's
    MaxRecursionDepth, else the scene's, else 6)."""
    path, _, cam = spec.partition("@")
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise SystemExit("bench: --scene-file %s: no such file" % path)
    root = parse_scene(path).getroot()
    cams = list(root.find("Cameras")) if root.find("Cameras") is not None else []
    k = int(cam) if cam else 1
    if not 1 <= k <= len(cams):
        raise SystemExit("bench: --scene-file %s: camera %d of %d" % (path, k, len(cams)))
    c = cams[k - 1]
    w, h = (int(x) for x in c.find("ImageResolution").text.split())
    f = long_side / max(w, h)
    res = (max(1, round(w * f)), max(1, round(h * f)))
    depth = 6
    for el in (c.find("MaxRecursionDepth"), root.find("MaxRecursionDepth")):
        if el is not None and el.text and el.text.strip():
            depth = int(el.text)
            break
    name = os.path.splitext(os.path.basename(path))[0] + ("-cam%d" % k if k > 1 else "")
    return dict(name=name, path=path, camera=k, res=res, depth=depth, ref_spp=ref_spp, user=True)


def user_scene_copy(sc, tmpdir, depth):
    """The copy of a --scene-file scene both renderers render: only its chosen camera (ImageName img.exr, the
    reduced resolution, no NumSamples, path traced (a camera that is not gets Renderer PathTracing with
    --path-params or MultipleImportanceSampling), Russian roulette removed from its RendererParams), file paths
    (PLY, texture images) made absolute, MaxRecursionDepth set where clrt reads it when depth differs."""
    tree = parse_scene(sc["path"])  # a JSON scene is rendered by both from its XML transliteration
    root = tree.getroot()
    base = os.path.dirname(sc["path"])
    for el in root.iter():
        if "plyFile" in el.attrib and not os.path.isabs(el.attrib["plyFile"]):
            el.attrib["plyFile"] = os.path.join(base, el.attrib["plyFile"])
    for img in root.iter("Image"):
        if img.text and img.text.strip() and not os.path.isabs(img.text.strip()):
            img.text = os.path.join(base, img.text.strip())
    cams = root.find("Cameras")
    keep = list(cams)[sc["camera"] - 1]
    for c in list(cams):
        if c is not keep:
            cams.remove(c)

    def set_child(parent, tag, text):
        el = parent.find(tag)
        if el is None:
            el = ET.SubElement(parent, tag)
        el.text = text

    set_child(keep, "ImageName", "img.exr")
    set_child(keep, "ImageResolution", "%d %d" % sc["res"])
    for el in keep.findall("NumSamples"):
        keep.remove(el)
    rp = keep.find("RendererParams")
    notes = sc.setdefault("notes", [])  # kept once each: make_scene may copy the scene more than once

    def note(text):
        if text not in notes:
            notes.append(text)

    if (keep.findtext("Renderer") or "").strip() != "PathTracing":
        # Mitsuba's side is `path`: a camera the scene renders otherwise (direct lighting, the classic
        # recursive tracer) is made path traced, with --path-params or else MIS, the strategy `path` uses.
        set_child(keep, "Renderer", "PathTracing")
        if rp is None:
            rp = ET.SubElement(keep, "RendererParams")
        old = (rp.text or "").strip()
        rp.text = sc.get("params") or "MultipleImportanceSampling"
        note("the camera made path traced in clrt (Renderer PathTracing, RendererParams '%s'; it had '%s')"
             % (rp.text, old))
    elif sc.get("params"):
        if rp is None:
            rp = ET.SubElement(keep, "RendererParams")
        if (rp.text or "").split() != sc["params"].split():
            note("RendererParams '%s' replaced by '%s' (--path-params)" % ((rp.text or "").strip(), sc["params"]))
        rp.text = sc["params"]
    own = (rp.text or "").split() if rp is not None else []
    if not sc.get("params") and not ({"MultipleImportanceSampling", "NextEventEstimation", "MIS_POWER", "MIS_BALANCE",
                                      "MIS_01"} & set(own)):
        # `path` always samples the lights (next-event estimation with MIS): a camera that does not is a
        # different estimator, far noisier wherever lights are small, and its efficiencies say so.
        note("clrt renders the camera's own strategy '%s', without next-event estimation, which Mitsuba's path "
             "always does: --path-params MultipleImportanceSampling compares the same strategy" % " ".join(own))
    if rp is not None and "RussianRoulette" in (rp.text or "").split():
        rp.text = " ".join(x for x in rp.text.split() if x != "RussianRoulette")
        note("RussianRoulette removed from clrt's RendererParams (it lifts the depth cap; Mitsuba renders at the cap)")
    if depth != sc["depth"]:
        set_child(keep if keep.find("MaxRecursionDepth") is not None else root, "MaxRecursionDepth", str(depth))
    out = os.path.join(tmpdir, "%s-d%d.xml" % (sc["name"], depth))
    tree.write(out)
    return out


def make_scene(sc, tmpdir, depth=None, params="MultipleImportanceSampling", area_light=False):
    """The scene copy both renderers render (see the module comment)."""
    depth = sc["depth"] if depth is None else depth
    if sc.get("user"):
        return user_scene_copy(sc, tmpdir, depth)
    if sc["path"] == VEACH:
        return veach_scene(sc, depth, tmpdir, params, area_light)
    p = bench_path.make_scene(dict(sc, name=sc["name"] + "-d%d" % depth), params, tmpdir, "mi")
    s = open(p).read()
    s = s.replace("<MaxRecursionDepth>40</MaxRecursionDepth>", "<MaxRecursionDepth>%d</MaxRecursionDepth>" % depth)
    if sc.get("glass"):
        s = s.replace('<SpecularReflectance>0.3 0.3 0.3</SpecularReflectance><AbsorptionCoefficient>0.01 0.01 0.01'
                      '</AbsorptionCoefficient>', '<SpecularReflectance>0 0 0</SpecularReflectance>')
        assert "AbsorptionCoefficient" not in s
    open(p, "w").write(s)
    return p


# ------------------------------------------------------------------------------------------- renderers
def clrt_render(B, clrt, scene, spp, seed):
    """(times, image): clrt's render stage, process wall and CPU seconds (user + system of the child)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    st, img, _ = clrt.render(scene, spp, seed)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return dict(t=st["render"], wall=st["wall"], cpu=cpu), img


class MitsubaPath:
    """A converted path-traced scene; render() times mi.render (wall and process CPU)."""

    def __init__(self, B, mi, scene_path, variant, sampler="independent", open_lights="two-sided"):
        self.mi = mi
        self.open_lights = open_lights
        d, self.warnings = to_mitsuba.scene_dict(scene_path, 1, warn=B.log, path_tracing=True, open_lights=open_lights)
        d["sensor"]["sampler"]["type"] = sampler
        self.max_depth = d["integrator"]["max_depth"]
        self.scene = mi.load_dict(to_mitsuba.materialize(d, mi))
        self.variant = variant

    def image(self, spp, seed):
        return np.array(self.mi.render(self.scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]

    def render(self, spp, seed):
        c0, t0 = time.process_time(), time.perf_counter()
        img = self.image(spp, seed)
        t, cpu = time.perf_counter() - t0, time.process_time() - c0
        return dict(t=t, wall=t, cpu=cpu), img

    def high(self, spp, seed0):
        n = max(1, spp // MI_PASS)
        return sum(self.image(min(spp, MI_PASS), seed0 + 7919 * k) for k in range(n)) / n


def mitsuba_reference(B, ms, sc, scene_path, cache, refresh):
    """Mitsuba's two independent halves, cached like clrt's (the scene's hash, the converter's and the variant in
    the name)."""
    d = os.path.join(cache, "%s-mitsuba-path-%s-%s-c%s-%d%s" % (sc["name"], ms.variant, B.scene_hash(scene_path),
                                                               to_mitsuba.code_hash(), sc["ref_spp"],
                                                               "" if ms.open_lights == "two-sided" else "-" + ms.open_lights))
    files = [os.path.join(d, f) for f in ("half_a.npy", "half_b.npy")]
    if not refresh and all(os.path.exists(f) for f in files):
        B.log("  mitsuba reference %s (cached)" % os.path.basename(d))
        return [np.load(f).astype(np.float64) for f in files]
    os.makedirs(d, exist_ok=True)
    B.log("  mitsuba reference: 2 x %d spp ..." % (sc["ref_spp"] // 2))
    halves = [ms.high(sc["ref_spp"] // 2, s) for s in B.REF_SEEDS]
    for f, v in zip(files, halves):
        np.save(f, v.astype(np.float32))
    return halves


def floor_of(a, b):
    ref = 0.5 * (a + b)
    return ref, float(np.mean((a - b) ** 2 / (ref ** 2 + B_EPS)) / 4.0)


B_EPS = 1e-2  # bench.py's EPS_REL with W = 1 (HDR scenes)


def agreement(cref, mref):
    """Per-channel mean ratios Mitsuba/clrt of the two references, and whether all are within 1%."""
    ratio = mref.reshape(-1, 3).mean(0) / np.maximum(cref.reshape(-1, 3).mean(0), 1e-30)
    return ratio, bool(np.all(np.abs(ratio - 1.0) <= 0.01))


# ------------------------------------------------------------------------------------------------ runs
def setup_cpu(B, clrt, scene, runs):
    """clrt's process CPU seconds outside the render: the median of 1-spp runs (parse, BVH, device and
    kernel-cache set-up, output; the 1 spp itself is left in, a small overestimate)."""
    return B.med([clrt_render(B, clrt, scene, 1, 0)[0]["cpu"] for _ in range(runs)])


def run_scene(B, clrt, mi, a, sc, tmp):
    """References, agreement, and every (spp, run) of both renderers; returns (rows, runs_rows, meta)."""
    scene = make_scene(sc, tmp)
    B.log("%s (%dx%d, clrt depth %d, %s, no roulette)" % (sc["name"], sc["res"][0], sc["res"][1], sc["depth"],
                                                        "its own RendererParams" if sc.get("user") else "MIS"))
    samplers = a.path_mi_samplers
    mss = {smp: MitsubaPath(B, mi, scene, a.mitsuba_variant, smp, sc.get("open_lights", "two-sided")) for smp in samplers}
    ms = mss[samplers[0]]  # the reference's (any sampler is unbiased; the cache key names no sampler)
    cref, cmeta = B.reference(clrt, sc, scene, "default", a.refs, True, a.refresh_refs)
    mref, mfloor = floor_of(*mitsuba_reference(B, ms, sc, scene, a.refs, a.refresh_refs))
    ratio, agree = agreement(cref, mref)
    B.log("  mean Mitsuba/clrt per channel %s: %s" % (" ".join("%.4f" % r for r in ratio),
                                                      "agree" if agree else "DISAGREE (> 1%)"))
    meta = dict(scene=sc["name"], res="%dx%d" % sc["res"], clrt_depth=sc["depth"], mitsuba_max_depth=ms.max_depth,
                ref_spp=sc["ref_spp"], clrt_floor=cmeta["relmse"], mitsuba_floor=mfloor, ratio=ratio, agree=agree,
                refs_relmse=B.rel_mse(mref, cref, 1.0), warnings=sc.get("notes", []) + ms.warnings)
    for m in mss.values():
        m.image(4, 0)  # warm-up (Dr.Jit compiles once per size)
    meta["clrt_setup_cpu"] = setup_cpu(B, clrt, scene, 3)
    spps = [s for s in (a.spp_list or SPP)]
    runs = []
    for spp in spps:
        for k in range(a.runs):  # run k of both back to back: drift hits both alike
            for who in ["clrt"] + [mitsuba_label(smp) for smp in samplers]:
                if who == "clrt":
                    t, img = clrt_render(B, clrt, scene, spp, k + 1)
                else:
                    t, img = mss[who.split("-")[-1] if "-" in who else "independent"].render(spp, k + 1)
                ref, floor = (cref, cmeta["relmse"]) if who == "clrt" else (mref, mfloor)
                if who == "clrt":
                    t["cpu_render"] = max(t["cpu"] - meta["clrt_setup_cpu"], 1e-6)
                else:
                    t["cpu_render"] = t["cpu"]
                e = B.rel_mse(img, ref, 1.0)
                runs.append(dict(scene=sc["name"], renderer=who, spp=spp, seed=k + 1, time_s=t["t"], wall_s=t["wall"],
                                 cpu_s=t["cpu"], cpu_render_s=t["cpu_render"], relmse=e, relmse_net=max(e - floor, 1e-12)))
                B.log("  %-7s spp %4d seed %d: %.3f s (wall %.3f, CPU %.3f)  relMSE %.4g" % (
                    who, spp, k + 1, t["t"], t["wall"], t["cpu_render"], e))
    return summarize(B, sc, runs, spps, [mitsuba_label(smp) for smp in samplers]), runs, meta


def mitsuba_label(sampler):
    """The runs' renderer name of a Mitsuba sampler ("mitsuba" for its default, independent)."""
    return "mitsuba" if sampler == "independent" else "mitsuba-" + sampler


def summarize(B, sc, runs, spps, labels):
    rows = []
    for label in labels:
        rows += summarize_one(B, sc, [r for r in runs if r["renderer"] in ("clrt", label)], spps, label)
    return rows


def summarize_one(B, sc, runs, spps, label):
    """One row per spp: medians of both renderers, efficiencies, the ratio and its two factors (wall and
    CPU), and the ratio's spread over run pairs of equal seed."""
    rows = []
    for spp in spps:
        c = [r for r in runs if r["renderer"] == "clrt" and r["spp"] == spp]
        m = [r for r in runs if r["renderer"] == label and r["spp"] == spp]
        row = dict(scene=sc["name"], spp=spp, runs=len(c), mitsuba_sampler=label.split("-")[-1] if "-" in label
                   else "independent")
        for who, rs in (("clrt", c), ("mitsuba", m)):
            for k in ("time_s", "wall_s", "cpu_render_s", "relmse", "relmse_net"):
                row["%s_%s" % (who, k)] = B.med([r[k] for r in rs])
            row[who + "_eff"] = 1.0 / (row[who + "_relmse_net"] * row[who + "_time_s"])
            row[who + "_eff_cpu"] = 1.0 / (row[who + "_relmse_net"] * row[who + "_cpu_render_s"])
        row["time_factor"] = row["mitsuba_time_s"] / row["clrt_time_s"]
        row["cpu_factor"] = row["mitsuba_cpu_render_s"] / row["clrt_cpu_render_s"]
        row["noise_factor"] = row["mitsuba_relmse_net"] / row["clrt_relmse_net"]
        row["eff_ratio"] = row["clrt_eff"] / row["mitsuba_eff"]
        row["eff_ratio_cpu"] = row["clrt_eff_cpu"] / row["mitsuba_eff_cpu"]
        pairs = [(y["relmse_net"] * y["time_s"]) / (x["relmse_net"] * x["time_s"]) for x, y in zip(c, m)]
        cpairs = [(y["relmse_net"] * y["cpu_render_s"]) / (x["relmse_net"] * x["cpu_render_s"]) for x, y in zip(c, m)]
        row["eff_ratio_min"], row["eff_ratio_max"] = min(pairs), max(pairs)
        row["eff_ratio_cpu_min"], row["eff_ratio_cpu_max"] = min(cpairs), max(cpairs)
        rows.append(row)
    return rows


# ---------------------------------------------------------------------------------------------- report
def plot(name, runs, meta, path):
    """relMSE (less each reference's own) against wall and against CPU seconds, every run, both renderers."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(13, 4.8))
    for who, col in zip(["clrt"] + sorted({r["renderer"] for r in runs} - {"clrt"}), ("C0", "C3", "C2", "C1")):
        rs = [r for r in runs if r["renderer"] == who]
        for i, key in enumerate(("time_s", "cpu_render_s")):
            ax[i].scatter([r[key] for r in rs], [r["relmse_net"] for r in rs], color=col, s=14, label=who)
            spps = sorted({r["spp"] for r in rs})
            med = lambda k, s: float(np.median([r[k] for r in rs if r["spp"] == s]))
            ax[i].plot([med(key, s) for s in spps], [med("relmse_net", s) for s in spps], color=col, lw=1)
    for i, lab in enumerate(("render wall time [s] (clrt: render stage; Mitsuba: mi.render)",
                             "render CPU time [s] (process user+system; clrt less its set-up)")):
        ax[i].set_xscale("log")
        ax[i].set_yscale("log")
        ax[i].grid(True, which="both", alpha=0.3)
        ax[i].set_xlabel(lab)
        ax[i].set_ylabel("relMSE - reference's own (points: runs; lines: medians)")
        ax[i].legend()
    fig.suptitle("%s %s: clrt MIS (depth %d) vs Mitsuba 3 path (max_depth %d), 16/64/256 spp" % (
        name, meta["res"], meta["clrt_depth"], meta["mitsuba_max_depth"]))
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def report(B, a, metas, rows, seconds, device_name):
    lines = ["## Path tracing against Mitsuba 3 (issue 32)", "",
             ("bench/bench_mitsuba_path.py, Mitsuba %s `%s`, %d threads each (clrt: `--device %s`, %s); %d runs "
              "per point; %.0f s. Time: wall of the render (clrt's render stage, Mitsuba's mi.render after a "
              "warm-up) and process CPU (user+system; clrt's less the median CPU of a 1-spp run: set-up). relMSE "
              "(W = 1) against each renderer's own reference, less that reference's own estimated relMSE." % (
                 a.mi_version, a.mitsuba_variant, a.threads, a.device or "cpu", device_name, a.runs, seconds)), "",
             "| scene | size | clrt depth / Mitsuba max_depth | ref spp | mean Mitsuba/clrt (R G B) | agree | relMSE between refs |",
             "|---|---|---|---|---|---|---|"]
    for m in metas:
        lines.append("| %s | %s | %d / %d | %d | %s | %s | %.3g |" % (
            m["scene"], m["res"], m["clrt_depth"], m["mitsuba_max_depth"], m["ref_spp"],
            " ".join("%.4f" % r for r in m["ratio"]), "yes" if m["agree"] else "**no**", m["refs_relmse"]))
    lines += ["", "| scene | spp | Mitsuba sampler | clrt s (CPU) | Mitsuba s (CPU) | clrt relMSE | Mitsuba relMSE | time factor (CPU) | "
              "noise factor | efficiency clrt/Mitsuba [min-max] | by CPU [min-max] |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    agrees = {m["scene"]: m["agree"] for m in metas}
    for r in rows:
        # A scene whose references' means disagree renders two different images: its efficiency is shown,
        # unmarked and flagged, but compares nothing.
        eff = "**%.2f** [%.2f-%.2f]" if agrees.get(r["scene"], True) else "%.2f [%.2f-%.2f] (means disagree)"
        lines.append(("| %s | %d | %s | %.3g (%.3g) | %.3g (%.3g) | %.3g | %.3g | %.2f (%.2f) | %.2f | " + eff + " | " + eff + " |") % (
                         r["scene"], r["spp"], r["mitsuba_sampler"], r["clrt_time_s"], r["clrt_cpu_render_s"], r["mitsuba_time_s"],
                         r["mitsuba_cpu_render_s"], r["clrt_relmse_net"], r["mitsuba_relmse_net"], r["time_factor"],
                         r["cpu_factor"], r["noise_factor"], r["eff_ratio"], r["eff_ratio_min"], r["eff_ratio_max"],
                         r["eff_ratio_cpu"], r["eff_ratio_cpu_min"], r["eff_ratio_cpu_max"]))
    lines += ["", "Efficiency ratio = time factor (Mitsuba s / clrt s) x noise factor (Mitsuba relMSE / clrt relMSE); "
              "> 1: clrt better. Spread: over run pairs of equal seed. Plots: mitsuba_path_<scene>.png.", ""]
    for m in metas:
        if not m["agree"]:
            lines.append("**%s: the references' means disagree by more than 1%%: the two renderers do not render the "
                         "same image (see the conversion warnings), so its efficiencies compare nothing.**" % m["scene"])
    for m in metas:
        lines.append("Conversion warnings, %s: %s" % (m["scene"], "; ".join(m["warnings"]) or "none"))
    return lines + [""]


def depth_check(B, clrt, mi, a, tmp, spp=1024):
    """The depth mapping: the box (64x64) at clrt depths 0, 1 against Mitsuba max_depth d+1, d+2, d+3."""
    import to_mitsuba
    lines = ["### Depth mapping (hw6 box 64x64, %d spp, MIS)" % spp, "",
             "| clrt depth | Mitsuba max_depth | mean Mitsuba/clrt (R G B) |", "|---|---|---|"]
    sc = dict(SCENES[0], res=(64, 64))
    for d in (0, 1):
        scene = make_scene(sc, tmp, depth=d)
        _, cimg = clrt_render(B, clrt, scene, spp, 5)
        dd, _ = to_mitsuba.scene_dict(scene, 1, path_tracing=True, open_lights=sc.get("open_lights", "two-sided"))
        for md in (d + 1, d + 2, d + 3):
            dd["integrator"].update(max_depth=md, rr_depth=md + 1)
            img = np.array(mi.render(mi.load_dict(to_mitsuba.materialize(dd, mi)), spp=spp, seed=5))[..., :3]
            r = img.reshape(-1, 3).mean(0) / cimg.reshape(-1, 3).mean(0)
            lines.append("| %d | %d | %s |" % (d, md, " ".join("%.4f" % x for x in r)))
            B.log("  depth check: clrt %d, Mitsuba %d: %s" % (d, md, lines[-1]))
    return lines + [""]


def main(B, clrt, a):
    """bench.py --mitsuba-path: every scene above; writes the CSVs, plots and mitsuba_path_report.md."""
    import shutil
    import tempfile
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(a.mitsuba_variant)
    import mitsuba_course_brdf
    mitsuba_course_brdf.register()  # glossy course materials (to_mitsuba_path.course_brdf)
    a.threads = os.cpu_count() or 2
    dr.set_thread_count(a.threads)
    a.mi_version = mi.__version__
    a.spp_list = [int(x) for x in a.spp.split(",") if x] if a.spp else None
    a.path_mi_samplers = [x for x in a.mitsuba_samplers.split(",") if x] or ["independent"]
    tmp = tempfile.mkdtemp(prefix="clrt-bench-mipath-")
    wanted = set(filter(None, a.scenes.split(",")))
    scenes = [s for s in SCENES if os.path.exists(s["path"]) and (not wanted or s["name"] in wanted)]
    if a.scene_file:
        scenes = [dict(user_scene(x, a.path_res, a.path_ref_spp), params=a.path_params) for x in a.scene_file.split(",") if x]
        if a.depth_check:
            raise SystemExit("bench: --depth-check runs on the hw6 box, not with --scene-file")
    device_name, out = B.device_folder(clrt, make_scene(scenes[0], tmp), a)
    B.log("bench: path tracing against Mitsuba %s (%s), %d threads; device '%s' -> %s" % (
        a.mi_version, a.mitsuba_variant, a.threads, device_name, out))
    t0, rows, runs, metas = time.perf_counter(), [], [], []
    extra = depth_check(B, clrt, mi, a, tmp) if a.depth_check else []
    for sc in scenes:
        r, rr, meta = run_scene(B, clrt, mi, a, sc, tmp)
        rows += r
        runs += rr
        metas.append(meta)
        plot(sc["name"], rr, meta, os.path.join(out, "mitsuba_path_%s.png" % sc["name"]))
    cols = list(rows[0].keys()) if rows else []
    B.write_csv(os.path.join(out, "mitsuba_path.csv"), rows, cols)
    B.write_csv(os.path.join(out, "mitsuba_path_runs.csv"), runs, list(runs[0].keys()) if runs else [])
    rep = ["# clrt benchmark, path tracing against Mitsuba 3: %s" % device_name, ""]
    rep += report(B, a, metas, rows, time.perf_counter() - t0, device_name) + extra
    open(os.path.join(out, "mitsuba_path_report.md"), "w").write("\n".join(rep) + "\n")
    print("\n".join(rep))
    shutil.rmtree(tmp, ignore_errors=True)
    B.log("bench: wrote %s" % out)
