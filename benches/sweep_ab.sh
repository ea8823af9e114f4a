#!/bin/bash
# Alternates the renderer's cost sweep (issue #5) between binaries built from different
# commits, ROUNDS times, and prints every row tagged with its binary: how BENCHMARKS.md #5's
# before/after figures were taken. Build each binary with
#   git checkout COMMIT && cargo bench -p btf-render --bench sweep --no-run
# and copy the printed target/release/deps/sweep-<hash> aside (before the bench restructure the
# sweep was a test: CARGO_PROFILE_DEV_OPT_LEVEL=3 cargo test -p btf-render --test measure
# --no-run, binary target/debug/deps/measure-<hash>; the bench ignores the test's arguments).
# Sweep settings come from the environment (defaults: 128², c = 4,8,16,32, 31 frames).
# Example: benches/quiet.sh benches/sweep_ab.sh 2 /tmp/measure_old /tmp/measure_new
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,10p' "$0" >&2
  exit 2
fi
rounds=$1
shift
cd "$(dirname "$0")/../btf-render"
for _ in $(seq "$rounds"); do
  for bin in "$@"; do
    BTF_SWEEP_SIZE=${BTF_SWEEP_SIZE:-128} BTF_SWEEP_COMPONENTS=${BTF_SWEEP_COMPONENTS:-4,8,16,32} \
      BTF_SWEEP_REPEATS=${BTF_SWEEP_REPEATS:-31} "$bin" cost_sweep --ignored --nocapture 2>&1 |
      grep -E '^\| [0-9]+ \|' | sed "s|^|$(basename "$bin") |"
  done
done
