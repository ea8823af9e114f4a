#!/usr/bin/env bash
# Stores on disk (issue #25): OLD = binary before the change (uncompressed chunks),
# NEW = this branch (zstd). Same run, same machine.
set -u
OLD=$1; NEW=$2; W=$3; cd $W
for n in 16 64; do
  for tag in old new; do
    B=$OLD; [ $tag = new ] && B=$NEW
    rm -rf m$n-$tag.btf
    /usr/bin/time -f "$tag synth $n: %e s" $B synth material --kind lambert --size $n -o m$n-$tag.btf >/dev/null
    echo "$tag $n: du $(du -sk m$n-$tag.btf | cut -f1) KiB, apparent $(du -sk --apparent-size m$n-$tag.btf | cut -f1) KiB, files $(find m$n-$tag.btf -type f | wc -l), dirs $(find m$n-$tag.btf -type d | wc -l), chunk bytes $(find m$n-$tag.btf/normtextures/c -type f -printf '%s\n' | awk '{s+=$1} END {print s}')"
  done
  for tag in old new; do
    for r in 1 2; do
      rm -rf e$n-$tag.eig
      /usr/bin/time -f "compress (new binary) from $tag store $n, round $r: %e s" $NEW compress m$n-$tag.btf -c 8 -o e$n-$tag.eig >/dev/null 2>/tmp/err.txt; tail -1 /tmp/err.txt
    done
    echo "eigen $n from $tag: du $(du -sk e$n-$tag.eig | cut -f1) KiB"
  done
done
