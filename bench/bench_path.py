"""bench_path.py — the path-traced part of the benchmark (issue 16): error against time for every path
tracing strategy, and which one is most efficient per scene. Called by bench.py (`--path-only`, or after
the other scenes unless `--no-path`); reads nothing but the scenes below.

Scenes (copies made at run time from ../shared, nothing committed): the hw6 path box
(cornellbox_jaroslav_path_diffuse.xml, camera 1's view) and the same box with the yellow sphere a
dielectric as in the course's later package (scripts/path_glass_box.sh). In both the PointLight is
removed (a BSDF-sampled path can never reach a point light, so without it every strategy estimates the
same image; the later package's glass box has none either) and MaxRecursionDepth is 40 (so the depth-capped
strategies and the Russian-roulette ones, which have no cap, estimate the same image too: the tail is far
below the noise).

Strategies (the camera's RendererParams): uniform (none), cosine (ImportanceSampling), NEE, NEE+IS, MIS
(clrt's MultipleImportanceSampling), each without and with RussianRoulette. Reference: MIS at ref_spp as two
independent halves (bench.py's reference(): seeds 1000001/2, cached under --refs). Per point: median
render time and relMSE over --runs seeds; efficiency = 1/(relMSE x render s).

Writes into the results folder: path.csv (one row per scene, strategy, spp), path_runs.csv, path_<scene>.png
(left: relMSE against render time, one curve per strategy, RR dashed, the reference's noise floor grey;
middle: convergence, relMSE less the reference's own against spp, with a 1/spp guide; right: efficiency
against spp) and returns the report's lines (the efficiency table, the best strategy per spp in bold,
and each strategy's convergence slope: the least-squares slope of log(relMSE - reference relMSE) against
log spp, -1 for an unbiased estimator of finite variance)."""
import os
import re

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "scenes"))
BOX = os.path.join(SHARED, "hw6", "cornellbox_jaroslav_path_diffuse.xml")

PATH_SCENES = [
    dict(name="hw6_box_path", path=BOX, res=(128, 128), spp=[4, 16, 64], ref_spp=1024, glass=False),
    dict(name="hw6_glass_box_path", path=BOX, res=(128, 128), spp=[4, 16, 64], ref_spp=1024, glass=True),
]
BASE = [("uniform", ""), ("cosine", "ImportanceSampling"), ("NEE", "NextEventEstimation"),
        ("NEE+IS", "NextEventEstimation ImportanceSampling"), ("MIS", "MultipleImportanceSampling")]
STRATEGIES = [(n, p) for n, p in BASE] + [(n + "+RR", (p + " RussianRoulette").strip()) for n, p in BASE]
GLASS = ('<Material id="9" BRDF="2" type="dielectric"><AmbientReflectance>0 0 0</AmbientReflectance>'
         '<DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0.3 0.3 0.3</SpecularReflectance>'
         '<AbsorptionCoefficient>0.01 0.01 0.01</AbsorptionCoefficient><RefractionIndex>1.5</RefractionIndex></Material>')


def make_scene(sc, params, tmpdir, label):
    """The scene copy for one strategy: camera 1 only, ImageName img.exr, the bench resolution, the given
    RendererParams, MaxRecursionDepth 40, no PointLight; the glass variant's yellow sphere a dielectric."""
    s = open(sc["path"]).read()
    s = re.sub(r"<MaxRecursionDepth>\d+</MaxRecursionDepth>", "<MaxRecursionDepth>40</MaxRecursionDepth>", s)
    s = re.sub(r"<PointLight id=\"1\">.*?</PointLight>", "", s, flags=re.S)
    cam = re.findall(r"<Camera id=.*?</Camera>", s, flags=re.S)[0]
    cam = re.sub(r"<ImageName>.*?</ImageName>", "<ImageName>img.exr</ImageName>", cam)
    cam = re.sub(r"<ImageResolution>.*?</ImageResolution>", "<ImageResolution>%d %d</ImageResolution>" % sc["res"], cam)
    cam = re.sub(r"<RendererParams>.*?</RendererParams>", "<RendererParams>%s</RendererParams>" % params, cam)
    s = re.sub(r"<Cameras>.*</Cameras>", "<Cameras>\n" + cam + "\n</Cameras>", s, flags=re.S)
    if sc["glass"]:
        s = s.replace("</Materials>", GLASS + "\n</Materials>")
        s, n = re.subn(r"(<Sphere id=\"1\">\s*<Material>)5(</Material>)", r"\g<1>9\g<2>", s)
        assert n == 1
    assert "<PointLight" not in s and s.count("<Camera ") == 1
    out = os.path.join(tmpdir, "%s-%s.xml" % (sc["name"], re.sub(r"[^A-Za-z0-9]+", "_", label)))
    open(out, "w").write(s)
    return out


def convergence_slope(rs, floor):
    """Slope of log(relMSE - floor) against log spp over a strategy's rows (floor: the reference's own
    relMSE, which every comparison against it contains); None with fewer than two usable points."""
    pts = [(r["spp"], r["relmse"] - floor) for r in rs if r["relmse"] - floor > 0]
    if len(pts) < 2:
        return None
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def plot_strategy(ax, label, rs, floor, colours):
    """One strategy's curves: relMSE against time, convergence and efficiency against spp (RR dashed)."""
    base, rr = label.replace("+RR", ""), label.endswith("+RR")
    kw = dict(color=colours[base], ls="--" if rr else "-", marker="s" if rr else "o", label=label)
    t = np.array([r["render_s"] for r in rs])
    e = np.array([r["relmse"] for r in rs])
    eerr = np.array([[r["relmse"] - r["relmse_min"] for r in rs], [r["relmse_max"] - r["relmse"] for r in rs]])
    ax[0].errorbar(t, e, yerr=eerr, capsize=2, **kw)
    spps = [r["spp"] for r in rs]
    ax[1].plot(spps, np.maximum(e - floor, 1e-12), **kw)
    ax[2].plot(spps, [r["efficiency"] for r in rs], **kw)


def plot(name, rows, floor, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(19, 4.8))
    colours = dict(zip([n for n, _ in BASE], plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    for label, _ in STRATEGIES:
        rs = sorted((r for r in rows if r["strategy"] == label), key=lambda r: r["spp"])
        if rs:
            plot_strategy(ax, label, rs, floor, colours)
    ax[0].axhline(floor, ls=":", color="gray", lw=1, label="reference noise floor")
    spps = sorted({r["spp"] for r in rows})
    top = max(r["relmse"] - floor for r in rows if r["spp"] == spps[0])
    ax[1].plot(spps, [top * spps[0] / x for x in spps], "k:", lw=1, label="1/spp")
    for a in ax:
        a.set_xscale("log")
        a.set_yscale("log")
        a.grid(True, which="both", alpha=0.3)
    ax[0].legend(fontsize=7, ncol=2)
    ax[0].set_xlabel("render time [s] (median; points: spp %s)" % "/".join(str(s) for s in sorted({r["spp"] for r in rows})))
    ax[0].set_ylabel("relMSE against the MIS reference (median; bars: min-max)")
    ax[1].set_xlabel("spp")
    ax[1].set_ylabel("relMSE - reference relMSE (convergence; dotted: 1/spp)")
    ax[2].set_xlabel("spp")
    ax[2].set_ylabel("efficiency 1/(relMSE x render s)")
    fig.suptitle("%s: error against time per path-tracing strategy (dashed: with Russian roulette)" % name)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def run_points(B, clrt, a, sc, paths, ref, meta, spps, runs_rows):
    """Every strategy of one scene at every spp, --runs times (run k of every strategy back to back: drift
    hits all alike); appends the single runs to runs_rows and returns the scene's rows (medians)."""
    scene_rows = []
    for spp in spps:
        by = {label: [] for label, _ in STRATEGIES}
        for run_ in range(a.runs):
            for label, _ in STRATEGIES:
                st, img, _ = clrt.render(paths[label], spp, run_ + 1)
                r = dict(scene=sc["name"], strategy=label, spp=spp, seed=run_ + 1, render=st["render"],
                         relmse=B.rel_mse(img, ref, 1.0), nonfinite=int((~np.isfinite(img)).sum()))
                runs_rows.append(r)
                by[label].append(r)
        for label, params in STRATEGIES:
            scene_rows.append(point_row(B, sc, label, params, spp, by[label], meta))
    return scene_rows


def point_row(B, sc, label, params, spp, rs, meta):
    """path.csv's row of one strategy at one spp from its runs rs."""
    t = [r["render"] for r in rs]
    e = [r["relmse"] for r in rs]
    row = dict(scene=sc["name"], strategy=label, params=params or "(none)", spp=spp, runs=len(rs),
               render_s=B.med(t), relmse=B.med(e), nonfinite=sum(r["nonfinite"] for r in rs))
    row["render_s_min"], row["render_s_max"] = B.spread(t)
    row["relmse_min"], row["relmse_max"] = B.spread(e)
    row["efficiency"] = 1.0 / (row["relmse"] * max(row["render_s"], 1e-9))
    row["ref_relmse"] = meta["relmse"]
    B.log("  %-10s spp %4d: render %.3fs  relMSE %.4g [%.4g-%.4g]  eff %.4g" % (
        label, spp, row["render_s"], row["relmse"], row["relmse_min"], row["relmse_max"], row["efficiency"]))
    return row


def table_row(label, params, scene_rows, meta, spps):
    """The report table's row of one strategy: its efficiency per spp (bold where best) and its slope."""
    slope = convergence_slope([x for x in scene_rows if x["strategy"] == label], meta["relmse"])
    t = dict(strategy=label, params=params or "(none)", slope="%.2f" % slope if slope is not None else "-")
    for spp in spps:
        r = next(x for x in scene_rows if x["strategy"] == label and x["spp"] == spp)
        best = max(x["efficiency"] for x in scene_rows if x["spp"] == spp)
        cell = "%.3g (%.3g s, %.3g)" % (r["efficiency"], r["render_s"], r["relmse"])
        t["spp %d" % spp] = ("**%s**" % cell) if r["efficiency"] == best else cell
    return t


def scene_report(B, a, sc, scene_rows, meta, spps):
    """The report's lines of one scene: one row per strategy, efficiency per spp, the best per spp in bold."""
    table = [table_row(label, params, scene_rows, meta, spps) for label, params in STRATEGIES]
    top = max((x for x in scene_rows if x["spp"] == spps[-1]), key=lambda x: x["efficiency"])
    return ["### %s (%dx%d; reference MIS %d spp, its relMSE %.3g)" % (sc["name"], sc["res"][0], sc["res"][1],
                                                                     meta["spp"], meta["relmse"]), "",
            B.md_table(table, ["strategy", "params"] + ["spp %d" % s for s in spps] + ["slope"]), "",
            "Cells: efficiency 1/(relMSE x render s) (render s, relMSE), medians of %d runs; bold: the most "
            "efficient strategy at that spp; slope: of log(relMSE - reference relMSE) against log spp (-1: "
            "converging as 1/spp). Most efficient at %d spp: **%s**. Non-finite pixels in all renders: %d."
            % (a.runs, spps[-1], top["strategy"], sum(x["nonfinite"] for x in scene_rows)),
            "Plot: path_%s.png." % sc["name"], ""]


def run(B, clrt, a, out, tmp):
    """B: the bench module (its reference(), rel_mse(), med(), spread(), md_table(), write_csv(), log()).
    Returns the report's lines."""
    import time
    rows, runs_rows, rep = [], [], ["## Path tracing: error against time per strategy (issue 16)", ""]
    wanted = set(filter(None, a.scenes.split(","))) if a.scenes else set()
    scenes = [s for s in PATH_SCENES if os.path.exists(s["path"]) and (not wanted or s["name"] in wanted)]
    if not scenes:
        B.log("bench: path scenes skipped (%s not present)" % BOX)
        return []
    t0 = time.perf_counter()
    for sc in scenes:
        B.log("%s (%dx%d, path traced, %d strategies)" % (sc["name"], sc["res"][0], sc["res"][1], len(STRATEGIES)))
        paths = {label: make_scene(sc, params, tmp, label) for label, params in STRATEGIES}
        ref, meta = B.reference(clrt, sc, paths["MIS"], "default", a.refs, True, a.refresh_refs)  # the MIS copy
        spps = sc["spp"][:2] if a.quick else sc["spp"]
        for label, _ in STRATEGIES:
            clrt.render(paths[label], 1, 0)  # warm-up: kernel cache
        scene_rows = run_points(B, clrt, a, sc, paths, ref, meta, spps, runs_rows)
        plot(sc["name"], scene_rows, meta["relmse"], os.path.join(out, "path_%s.png" % sc["name"]))
        rows += scene_rows
        rep += scene_report(B, a, sc, scene_rows, meta, spps)
    rep.insert(2, "Scenes, strategies and reference: bench/bench_path.py. %.0f s." % (time.perf_counter() - t0))
    rep.insert(3, "")
    B.write_csv(os.path.join(out, "path.csv"), rows,
                ["scene", "strategy", "params", "spp", "runs", "render_s", "render_s_min", "render_s_max", "relmse",
                 "relmse_min", "relmse_max", "efficiency", "ref_relmse", "nonfinite"])
    B.write_csv(os.path.join(out, "path_runs.csv"), runs_rows, ["scene", "strategy", "spp", "seed", "render", "relmse", "nonfinite"])
    return rep


def main_path_only(B, clrt, a):
    """bench.py --path-only: the path scenes alone; writes path_report.md into the results folder."""
    import shutil
    import tempfile
    tmp = tempfile.mkdtemp(prefix="clrt-bench-path-")
    device_name, out = B.device_folder(clrt, make_scene(PATH_SCENES[0], "", tmp, "probe"), a)
    B.log("bench: path scenes only; device '%s' -> %s; %d runs per point" % (device_name, out, a.runs))
    rep = ["# clrt benchmark, path tracing: %s" % device_name, ""] + run(B, clrt, a, out, tmp)
    open(os.path.join(out, "path_report.md"), "w").write("\n".join(rep) + "\n")
    print("\n".join(rep))
    shutil.rmtree(tmp, ignore_errors=True)
    B.log("bench: wrote %s" % out)
