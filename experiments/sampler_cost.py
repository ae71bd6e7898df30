"""sampler_cost.py — the cost of a pixel sampler apart from its noise: interleaved renders of one scene
(bench.py's prepare_scene at half resolution) with --sampler stratified and zsobol, alternating, each
timed by the process's CPU time (user + sys of the child: less sensitive than wall time to other jobs
on a shared machine) and by clrt's own `render=` seconds. Prints one line per run and the medians.
usage: python3 experiments/sampler_cost.py CLRT_EXE SCENE_NAME [spp] [pairs]"""
import os
import resource
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "bench"))
import bench  # noqa: E402


def main():
    exe, name = sys.argv[1], sys.argv[2]
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 16
    pairs = int(sys.argv[4]) if len(sys.argv) > 4 else 4
    sc = next(s for s in bench.SCENES if s["name"] == name)
    tmp = tempfile.mkdtemp(prefix="sampler-cost-")
    path, _ = bench.prepare_scene(dict(sc, res=(sc["res"][0] // 2, sc["res"][1] // 2)), tmp)
    res = {"stratified": ([], []), "zsobol": ([], [])}
    for k in range(pairs + 1):  # the first pair warms the kernel cache and is dropped
        for smp in ("stratified", "zsobol") if k % 2 == 0 else ("zsobol", "stratified"):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            p = subprocess.run([exe, "render", path, "-o", tmp, "--spp", str(spp), "--seed", str(k + 1), "--device",
                                os.environ.get("CLRT_DEVICE", "cpu"), "--sampler", smp], capture_output=True, text=True)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            render = float(p.stdout.split("render=")[1].split("s")[0])
            print("%s run %d: cpu %.2f s, render %.3f s" % (smp, k, cpu, render), flush=True)
            if k > 0:
                res[smp][0].append(cpu)
                res[smp][1].append(render)
    med = lambda v: sorted(v)[len(v) // 2]
    for smp, (c, r) in res.items():
        print("%s: median cpu %.2f s, median render %.3f s over %d runs" % (smp, med(c), med(r), len(c)))
    print("zsobol / stratified: cpu %.3f, render %.3f" % (med(res["zsobol"][0]) / med(res["stratified"][0]),
                                                         med(res["zsobol"][1]) / med(res["stratified"][1])))


if __name__ == "__main__":
    main()
