#!/usr/bin/env bash
# Runs every fuzz target, one after the other, for RUNS executions each (default 10^6)
# under a 1 GiB memory limit, at low priority, and writes a table of the figures.
#
#   bash fuzz/run_all.sh                      # all 13 targets, 10^6 executions each
#   RUNS=100000 bash fuzz/run_all.sh pvf obj_mesh
#   SANITIZER=none bash fuzz/run_all.sh       # if AddressSanitizer builds fail
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`); on a stable toolchain RUSTC_BOOTSTRAP=1
# lets it pass its nightly-only flags. Builds into fuzz/target (never the workspace's
# target/). Per target: the corpus starts from fuzz/seeds/<target>/ (make_seeds.sh) plus
# whatever fuzz/corpus/<target>/ already holds; findings go to fuzz/artifacts/<target>/;
# the libFuzzer log to fuzz/logs/<target>.log. The table goes to fuzz/logs/summary.md
# (and stdout; SUMMARY=FILE elsewhere, for runs in parallel). Exit status: 0 when no
# target found anything.
set -uo pipefail
cd "$(dirname "$0")"

RUNS=${RUNS:-1000000}
RSS_MB=${RSS_MB:-1024}
TIMEOUT_S=${TIMEOUT_S:-10}
SANITIZER=${SANITIZER:-address}
NICE=${NICE:-15}
TRIPLE=x86_64-unknown-linux-gnu
ALL=(envmap scene_toml obj_mesh capture_toml zarr_array btf_store
     eigen_store ubo2014 pvf raw_image ubo2003_image bcc blosc_frame)
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${ALL[@]}")

# Largest input per target (bytes): room for a small image / store / file of the format.
max_len() {
    case "$1" in
        envmap|raw_image|ubo2003_image) echo 16384 ;;
        capture_toml|eigen_store|pvf|ubo2014) echo 8192 ;;
        *) echo 4096 ;;
    esac
}

export RUSTC_BOOTSTRAP=1
[ -d seeds ] || bash make_seeds.sh >/dev/null
mkdir -p logs
echo "building all targets (sanitizer: $SANITIZER) ..." >&2
nice -n "$NICE" cargo fuzz build -s "$SANITIZER" >logs/build.txt 2>&1 \
    || { tail -30 logs/build.txt >&2; exit 2; }

bin_dir=target/$TRIPLE/release
summary=${SUMMARY:-logs/summary.md}
{
    echo "| target | max_len | executions | wall time | exec/s | peak RSS | corpus (files / bytes) | coverage (cov / ft) | findings |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---|"
} >"$summary"

status=0
for t in "${targets[@]}"; do
    corpus=corpus/$t
    artifacts=artifacts/$t
    mkdir -p "$corpus" "$artifacts"
    [ -d "seeds/$t" ] && cp -n seeds/"$t"/* "$corpus"/ 2>/dev/null
    len=$(max_len "$t")
    log=logs/$t.log
    echo "== $t: $RUNS runs, -max_len=$len, -rss_limit_mb=$RSS_MB" >&2
    start=$(date +%s.%N)
    nice -n "$NICE" "$bin_dir/$t" "$corpus" \
        -runs="$RUNS" -rss_limit_mb="$RSS_MB" -max_len="$len" -timeout="$TIMEOUT_S" \
        -artifact_prefix="$artifacts/" -print_final_stats=1 >"$log" 2>&1 &
    pid=$!
    wait "$pid"
    rc=$?
    end=$(date +%s.%N)
    # The targets write their inputs below /dev/shm/btf-fuzz-<pid>: remove that scratch.
    rm -rf "/dev/shm/btf-fuzz-$pid" "${TMPDIR:-/tmp}/btf-fuzz-$pid"
    wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.0f", b - a }')
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    eps=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
    last=$(grep -E '^#[0-9]+' "$log" | tail -1)
    cov=$(sed -n 's/.* cov: \([0-9]*\) ft: \([0-9]*\).*/\1 \/ \2/p' <<<"$last")
    files=$(find "$corpus" -type f | wc -l)
    bytes=$(du -sb "$corpus" | cut -f1)
    found=$(find "$artifacts" -type f | wc -l)
    if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
        kind=$(grep -m1 -oE 'ERROR: libFuzzer: [a-z-]+|ERROR: AddressSanitizer: [a-z-]+|panicked at [^:]+:[0-9]+' "$log")
        what="**exit $rc, $found artifact(s)${kind:+: $kind}**"
        status=1
    else
        what="none"
    fi
    row="| $t | $len | ${execs:-?} | ${wall} s | ${eps:-?} | ${rss:-?} MB | $files / $bytes | ${cov:-?} | $what |"
    echo "$row" >>"$summary"
    echo "$row" >&2
done
echo >&2
cat "$summary"
exit "$status"
