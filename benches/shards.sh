#!/bin/bash
# Sharded jobs (issue #23): total CPU time of a job split into N shards run as N concurrent
# processes (plus `btf finalize`) against the same job in one process, and throughput at
# shard counts 1, 2, 4. Self-contained: synthesises its inputs into a temporary folder.
#   benches/shards.sh [BTF_BINARY]        (default target/release/btf)
# Knobs: ROTATIONS (per environment, 2 environments; default 100 → 200 frames),
#        FRAME (frame size, default 128), TEX (material size, default 32),
#        STORE (compression store size, default 64), DTYPE (its dtype, default f32),
#        ROUNDS (default 2; the configurations are interleaved round by round),
#        KINDS (default "relight compress"), LP_NUM_THREADS (lavapipe's threads per process),
#        BIG_STORE (compress this existing store instead of synthesising one).
# Prints one line per run: wall seconds, CPU seconds (user + sys summed over every
# process of the run), frames or slots per wall second; then per configuration the median
# CPU and wall over the rounds with their range, and the median CPU against one process.
# The 256² compression of BENCHMARKS.md (#23):
#   KINDS=compress STORE=256 DTYPE=f16 ROUNDS=3 benches/shards.sh
set -euo pipefail
bin=$(realpath "${1:-${CARGO_TARGET_DIR:-target}/release/btf}")
rotations=${ROTATIONS:-100}; frame=${FRAME:-128}; tex=${TEX:-32}; store=${STORE:-64}
rounds=${ROUNDS:-2}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/shards.XXXX")
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
export BTF_NO_PROGRESS=1
q() { "$bin" "$@" > /dev/null; }
q synth material --kind corduroy --size "$tex" -o mat.btf
q compress mat.btf -c 8 -o mat.eig
q synth mesh --kind sphere -o sphere.obj
q synth env --kind sky --width 128 -o sky.exr
q synth env --kind studio --width 128 -o studio.exr
if [ -n "${BIG_STORE:-}" ]; then ln -s "$(realpath "$BIG_STORE")" big.btf  # an existing store
else case " ${KINDS:-compress} " in *" compress "*) q synth material --kind corduroy --size "$store" --dtype "${DTYPE:-f32}" -o big.btf ;; esac; fi
cat > scene.toml <<TOML
[output]
width = $frame
height = $frame
[[meshes]]
path = "sphere.obj"
[[materials]]
store = "mat.eig"
[camera]
projection = "perspective"
eye = [0.0, 2.5, 1.5]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov_y_deg = 40.0
[[lights]]
kind = "environment"
path = "sky.exr"
visibility_res = 16
[effects]
evaluation = "per-vertex"
components = 8
TOML
frames=$((2 * rotations))
relight=(relight scene.toml --env sky.exr --env studio.exr --rotations "$rotations")
compress=(compress big.btf -c 16)

# timed LABEL CMD…: runs CMD under GNU time, appends "wall user sys" to LABEL.t
timed() { local l=$1; shift; /usr/bin/time -f "%e %U %S" -a -o "$l.t" "$@" > /dev/null; }

# run_job KIND N ROUND: one run of the job in N shards (N = 0: one process, no --shard)
run_job() {
  local kind=$1 n=$2 r=$3 out
  if [ "$kind" = relight ]; then out=r$n.$r; else out=c$n.$r.eig; fi
  local -n cmd=$kind
  rm -f run.t
  local t0; t0=$(date +%s.%N)
  if [ "$n" = 0 ]; then
    timed run "$bin" "${cmd[@]}" -o "$out"
  else
    for i in $(seq 0 $((n - 1))); do
      timed run "$bin" "${cmd[@]}" -o "$out" --shard "$i/$n" &
    done
    wait
    timed run "$bin" finalize "$out"
  fi
  local t1; t1=$(date +%s.%N)
  python3 - "$kind" "$n" "$t0" "$t1" "$frames" <<'PY'
import sys
kind, n, t0, t1, frames = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
rows = [list(map(float, l.split())) for l in open("run.t") if l.strip() and l[0].isdigit()]
cpu = sum(u + s for _, u, s in rows)
wall = t1 - t0
units = frames if kind == "relight" else 81
label = "one process" if n == 0 else f"{n} shard(s)"
print(f"{kind:8} {label:12} wall {wall:7.2f} s  cpu {cpu:7.2f} s  {units / wall:7.2f} units/s", flush=True)
open(f"{kind}.cpu", "a").write(f"{n} {cpu} {wall}\n")
PY
}

for r in $(seq 1 "$rounds"); do
  for kind in ${KINDS:-relight compress}; do
    for n in 0 1 2 4; do run_job "$kind" "$n" "$r"; done
  done
done
python3 - <<'PY'
import collections
import os
for kind in os.environ.get("KINDS", "relight compress").split():
    runs = collections.defaultdict(list)
    for l in open(f"{kind}.cpu"):
        n, cpu, wall = l.split()
        runs[int(n)].append((float(cpu), float(wall)))
    med = lambda xs: sorted(xs)[len(xs) // 2] if len(xs) % 2 else sum(sorted(xs)[len(xs) // 2 - 1:len(xs) // 2 + 1]) / 2
    base = med([c for c, _ in runs[0]])
    for n in sorted(runs):
        cs = [c for c, _ in runs[n]]; ws = [w for _, w in runs[n]]
        cpu, wall = med(cs), med(ws)
        label = "one process" if n == 0 else f"{n} shard(s)"
        print(f"{kind:8} {label:12} median cpu {cpu:7.2f} s [{min(cs):.2f}-{max(cs):.2f}] "
              f"({100 * (cpu / base - 1):+5.1f} %), median wall {wall:7.2f} s [{min(ws):.2f}-{max(ws):.2f}]")
PY
