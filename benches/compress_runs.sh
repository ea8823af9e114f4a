#!/bin/bash
# The timing protocols of BENCHMARKS.md #2 (session 5), each run to a fresh output path.
# Run under benches/quiet.sh so that nothing else shares the cores, e.g.
#   benches/quiet.sh benches/compress_runs.sh strict 5 STORE.btf
# Modes (N runs each; BIN defaults to target/release/examples/compress_store):
#   back-to-back N STORE      runs one after another
#   sync N STORE              `sync` before each run
#   idle N STORE              4 s idle before each run
#   strict N STORE            session 4's protocol: previous output removed, `sync`, 4 s idle
#   interleaved N STORE SLOTS `sync` + 4 s idle, scikit-learn on the exported SLOTS folder
#                             after runs 2 and 4 (benches/sklearn_baseline.py)
#   ab N STORE BIN_A BIN_B    two binaries alternating, run by run
# Prints wall, user and sys time per run (GNU time) and, for ours, the JSON's seconds.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=$1; n=$2; store=$3
bin=${BIN:-target/release/examples/compress_store}
tmp=${TMPDIR:-/tmp}/compress_runs.$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT
run() { # label binary output
  /usr/bin/time -f "$1: %e s wall, %U s user, %S s sys, %M KB peak" "$2" "$store" "$3" 16 \
    > "$3.json"
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print('  seconds', round(d['seconds'], 3), 'rel_rmse', d['rel_rmse'])" "$3.json"
}
prev=""
for r in $(seq 1 "$n"); do
  out="$tmp/run$r.eig"
  case "$mode" in
    back-to-back) run "run $r" "$bin" "$out" ;;
    sync) sync; run "run $r" "$bin" "$out" ;;
    idle) sleep 4; run "run $r" "$bin" "$out" ;;
    strict)
      [ -n "$prev" ] && rm -rf "$prev"
      sync; sleep 4; run "run $r" "$bin" "$out"; prev=$out ;;
    interleaved)
      sync; sleep 4; run "run $r" "$bin" "$out"
      if [ "$r" = 2 ] || [ "$r" = 4 ]; then
        env -u OPENBLAS_CORETYPE -u OPENBLAS_L2_SIZE python3 benches/sklearn_baseline.py "$4" --components 16 | tail -1
      fi ;;
    ab) run "A run $r" "$4" "$out.a"; run "B run $r" "$5" "$out.b" ;;
    *) echo "unknown mode $mode" >&2; exit 2 ;;
  esac
done
