#!/usr/bin/env bash
# perf_kernels.sh — where a render's CPU time goes, by kernel function: `perf record -e cpu-clock` (a
# software clock: works in VMs without hardware counters) of one `clrt render`, then the functions with
# the most samples. PoCL compiles each kernel into a shared object with its symbols (Bvh_Traverse,
# EnvMap_Lookup, ...), so perf names the device functions that PoCL did not inline; the host's share
# (parse, BVH build) is listed too. `perf annotate -i OUT/perf.data -s FUNCTION --stdio` then shows the
# instructions (a load's consumer with most of a function's samples: a cache miss).
# usage: experiments/perf_kernels.sh SCENE [SPP] [OUT] [-- extra clrt render options]
#        SCENE: a scene file, or the name of a bench/bench.py scene (tt_diffuse, sphere_env_light_courtyard,
#        ...: its copy at the bench's resolution is made in OUT/scene with build/bench-venv's python, as
#        experiments/profile_stages.py does). Default SPP 32, OUT build/perf.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=$1; spp=${2:-32}; out=${3:-build/perf}
shift $(( $# < 3 ? $# : 3 ))
[ "${1:-}" = "--" ] && shift
command -v perf >/dev/null || { echo "perf_kernels.sh: needs perf (Debian: linux-perf)" >&2; exit 1; }
mkdir -p "$out/img"
case "$scene" in
  *.xml|*.json) ;;
  *) mkdir -p "$out/scene"
     scene=$(build/bench-venv/bin/python -c 'import sys; sys.path.insert(0, "bench"); import bench
sc = next(s for s in bench.SCENES if s["name"] == sys.argv[1]); print(bench.prepare_scene(sc, sys.argv[2])[0])' "$scene" "$out/scene") ;;
esac
perf record -q -e cpu-clock -F 2000 -g -o "$out/perf.data" build/clrt render "$scene" -o "$out/img" --spp "$spp" "$@" >/dev/null 2>&1
perf report -i "$out/perf.data" --no-children --sort dso,sym -g none 2>/dev/null | grep -v '^#' | grep -v '^$' | head -25
