#!/usr/bin/env bash
# Issue #24: per kernel path (BTF_SIMD=scalar|avx2|avx512, whichever this CPU runs), the
# visibility rasteriser of BENCHMARKS.md "Environment lighting library (issue #6)" and
# `btf synth material` at SIZE², one after the other in one run, with the CPU and the load.
#
#   benches/isa_paths.sh [SIZE] [OUT_DIR]        (SIZE default 64; OUT_DIR default /tmp/isa_paths.PID)
#
# Visibility: `cargo bench -p btf-light --bench visibility -- --quick --noplot` with
# BTF_SIMD set; its table has the rasteriser (whose ray lanes follow BTF_SIMD) and, in the
# same run, the ray cast it must equal (portable code on every path: the baseline).
# BTF_MEASURE_HIGH=1 for the 9160-vertex shirt (default: the 925-vertex one).
# Synthesis: `btf synth material --kind corduroy --size SIZE` under GNU time. The generator
# has no vector path of its own (btf-core/README.md, "Other hot loops"): BTF_SIMD changes
# nothing in it, so its rows show how much the machine's noise alone moves a figure.
# Environment: BTF (the btf binary; default $CARGO_TARGET_DIR/release/btf, else
# target/release/btf), PATHS (default: every path the CPU runs), KIND (default corduroy).
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-64}
out=${2:-/tmp/isa_paths.$$}
mkdir -p "$out"
btf=${BTF:-${CARGO_TARGET_DIR:-target}/release/btf}
kind=${KIND:-corduroy}

grep -m1 -E '^(model name|Model)' /proc/cpuinfo || true
flags=$(grep -m1 -E '^(flags|Features)' /proc/cpuinfo | cut -d: -f2)
echo "SIMD flags:$(for f in $flags; do case $f in avx*|fma|f16c|asimd*) printf ' %s' "$f";; esac; done)"
if [ -z "${PATHS:-}" ]; then
  PATHS=scalar
  has() { case " $flags " in *" $1 "*) return 0;; esac; return 1; }
  if [ "$(uname -m)" = aarch64 ]; then PATHS="scalar neon"
  elif has avx2 && has fma && has f16c; then
    PATHS="scalar avx2"; has avx512f && PATHS="$PATHS avx512"
  fi
fi
echo "paths: $PATHS; loadavg at start: $(cat /proc/loadavg)"

for p in $PATHS; do
  echo; echo "### visibility, BTF_SIMD=$p (loadavg before: $(cat /proc/loadavg))"
  BTF_SIMD=$p cargo bench -q -p btf-light --bench visibility -- --quick --noplot 2>&1 \
    | tee "$out/visibility-$p.txt" | sed -n '/^shirt/p;/^## visibility/,$p'
done

echo
echo "| synth material --kind $kind --size $size | wall s | user s | peak RSS MB | loadavg before |"
echo "|---|---:|---:|---:|---|"
for p in $PATHS; do
  rm -rf "$out/$kind$size-$p.btf"
  la=$(cat /proc/loadavg)
  BTF_SIMD=$p BTF_NO_PROGRESS=1 /usr/bin/time -f "%e %U %M" -o "$out/time-synth-$p.txt" \
    "$btf" synth material --kind "$kind" --size "$size" -o "$out/$kind$size-$p.btf" > /dev/null 2> "$out/synth-$p.err"
  read -r wall user rss < "$out/time-synth-$p.txt"
  echo "| BTF_SIMD=$p | $wall | $user | $((rss / 1024)) | $la |"
  rm -rf "$out/$kind$size-$p.btf"
done
echo; echo "loadavg at end: $(cat /proc/loadavg)"
