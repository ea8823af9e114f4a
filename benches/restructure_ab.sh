#!/usr/bin/env bash
# Same-run A/B of two `btf` binaries (issue #17: the restructure must not slow anything):
# the demo's numbers, `btf compress` (BENCHMARKS #2), frame times of the demo garment under a point light with shadow volumes
# and environment scenes of the demo (#5, #6: `--stats-json` frame_ms with --repeat) and the
# environment-light preparation (#6: first frame of the shirt scene with a cold cache).
# Runs alternate A, B, A, B … so load drifts hit both; the table gives medians and B/A.
#
#   benches/restructure_ab.sh OLD_BTF NEW_BTF OUT [ROUNDS]
set -euo pipefail
A=$1; B=$2; OUT=$3; ROUNDS=${4:-5}
mkdir -p "$OUT"; cd "$OUT"
export BTF_NO_PROGRESS=1
# Data: the demo of each binary (same embedded defaults), stores reused below.
for x in A B; do
    bin=${!x}
    [ -f demo-$x/report.md ] || "$bin" demo -o demo-$x > demo-$x.log 2>&1
done
S=$(cd "$(dirname "$0")" 2>/dev/null; pwd)
ms() { python3 -c 'import json,sys; print(json.load(sys.stdin)["frame_ms"])'; }
now() { date +%s.%N; }
: > times.csv
for r in $(seq 1 "$ROUNDS"); do
  for x in A B; do
    bin=${!x}
    t0=$(now); "$bin" compress demo-A/material.btf -c 16 -o c-$x.eig --fresh > /dev/null 2>&1 || \
        "$bin" compress demo-A/material.btf -c 16 -o c-$x.eig > /dev/null 2>&1; t1=$(now)
    echo "$x,compress,$(python3 -c "print(($t1-$t0)*1e3)")" >> times.csv
    for scene in scene-point scene-environment; do
      f=demo-A/$scene.toml
      [ -f "$f" ] || continue
      v=$("$bin" render "$f" -o r-$x-$scene.png --repeat 20 --stats-json 2>/dev/null | ms)
      echo "$x,frame:$scene,$v" >> times.csv
    done
    if [ -f demo-A/scene-environment.toml ]; then
      rm -rf demo-A/cache
      t0=$(now); "$bin" render demo-A/scene-environment.toml -o p-$x.png > /dev/null 2>&1; t1=$(now)
      echo "$x,envlight-prepare+frame,$(python3 -c "print(($t1-$t0)*1e3)")" >> times.csv
    fi
  done
done
python3 - <<'P'
import csv, statistics as st, collections
d = collections.defaultdict(list)
for x, k, v in csv.reader(open("times.csv")):
    d[(k, x)].append(float(v))
print("| measurement | A median (ms) | B median (ms) | B / A |")
print("|---|---:|---:|---:|")
for k in sorted({k for k, _ in d}):
    a, b = st.median(d[(k, "A")]), st.median(d[(k, "B")])
    print(f"| {k} | {a:.1f} | {b:.1f} | {b / a:.3f} |")
P
