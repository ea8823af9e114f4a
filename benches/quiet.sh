#!/bin/bash
# Runs "$@" with every other user-space process on the machine stopped (SIGSTOP) and resumes
# them afterwards (SIGCONT, also on Ctrl-C): how the "idle" figures in BENCHMARKS.md were
# taken on a shared 2-core machine. Kernel threads, PID 1 and this script's own ancestors keep
# running. Example: benches/quiet.sh target/release/examples/compress_store IN.btf OUT.eig 16
keep=" 1 $$ "
p=$$
while [ "$p" -gt 1 ]; do p=$(ps -o ppid= -p "$p" | tr -d ' '); keep="$keep$p "; done
pids=""
for q in $(ps -e -o pid= -o ppid= | awk '$2 != 2 && $1 != 2 {print $1}'); do
  case "$keep" in *" $q "*) ;; *) pids="$pids $q";; esac
done
trap 'kill -CONT $pids 2>/dev/null' EXIT
kill -STOP $pids 2>/dev/null
sleep 3
uptime
"$@"
