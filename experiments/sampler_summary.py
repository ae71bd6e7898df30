"""sampler_summary.py — summarises sampler_compare.py's CSV: per scene and spp the mean relMSE of each
sampler over the runs (min-max), the ratios stratified / zsobol of means and of medians (> 1: zsobol less noisy), the median
render seconds, and each sampler's convergence slope (least squares of log relMSE on log spp).
usage: python3 experiments/sampler_summary.py FILE.csv ..."""
import csv
import math
import sys
from collections import defaultdict


def slope(pts):
    xs = [math.log(s) for s, _ in pts]
    ys = [math.log(max(e, 1e-12)) for _, e in pts]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def main():
    rows = [r for f in sys.argv[1:] for r in csv.DictReader(open(f))]
    err, secs = defaultdict(list), defaultdict(list)
    for r in rows:
        k = (r["scene"], r["sampler"], int(r["spp"]))
        err[k].append(float(r["relmse"]))
        secs[k].append(float(r["seconds"]))
    scenes = sorted({k[0] for k in err}, key=lambda s: [r["scene"] for r in rows].index(s))
    print("| scene | spp | stratified | zsobol | independent | stratified / zsobol (means) | (medians) | s (strat, zsobol) |")
    print("|---|---|---|---|---|---|---|---|")
    mean = lambda v: sum(v) / len(v)
    med = lambda v: sorted(v)[len(v) // 2]
    slopes = []
    for sc in scenes:
        spps = sorted({k[2] for k in err if k[0] == sc})
        for spp in spps:
            cell = lambda smp: "%.4g (%.3g–%.3g)" % (mean(err[sc, smp, spp]), min(err[sc, smp, spp]), max(err[sc, smp, spp]))
            print("| %s | %d | %s | %s | %s | %.2f | %.2f | %.2f, %.2f |" % (
                sc, spp, cell("stratified"), cell("zsobol"), cell("independent"),
                mean(err[sc, "stratified", spp]) / mean(err[sc, "zsobol", spp]),
                med(err[sc, "stratified", spp]) / med(err[sc, "zsobol", spp]),
                med(secs[sc, "stratified", spp]), med(secs[sc, "zsobol", spp])))
        if len(spps) > 1:
            slopes.append((sc, {smp: slope([(s, mean(err[sc, smp, s])) for s in spps])
                                for smp in ("stratified", "zsobol", "independent")}))
    print()
    print("| scene | slope stratified | slope zsobol | slope independent |")
    print("|---|---|---|---|")
    for sc, d in slopes:
        print("| %s | %.2f | %.2f | %.2f |" % (sc, d["stratified"], d["zsobol"], d["independent"]))


if __name__ == "__main__":
    main()
