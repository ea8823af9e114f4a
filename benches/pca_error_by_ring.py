#!/usr/bin/env python3
"""Relative PCA error per ring of view slots (BENCHMARKS.md #4, "Per ring"): the per-slot
squared errors of `btf compress --json` over the per-slot energy of the BTF store, summed
over the slots of each ring of the store's view sampling.

Usage: python3 benches/pca_error_by_ring.py STORE.btf COMPRESS.json
e.g.   btf synth material --kind knit --size 64 -o knit64.btf
       btf compress knit64.btf -c 16 -o knit64.eig --json > knit64.json
       python3 benches/pca_error_by_ring.py knit64.btf knit64.json
"""
import json
import sys

import numpy as np


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    store, report = sys.argv[1], sys.argv[2]
    meta = json.load(open(f"{store}/normtextures/zarr.json"))
    views, lights = meta["shape"][0], meta["shape"][1]
    dtype = {"float32": "<f4", "float16": "<f2"}[meta["data_type"]]
    rings = json.load(open(f"{store}/zarr.json"))["attributes"]["btf"]["view_sampling"]["rings"]
    sse = {s["view"]: s["sse"] for s in json.load(open(report))["slots"]}
    if len(sse) != views:
        sys.exit(f"{report}: {len(sse)} slots, the store has {views}")
    energy = []
    for v in range(views):
        e = 0.0
        for l in range(lights):
            raw = open(f"{store}/normtextures/c/{v}/{l}/0/0/0", "rb").read()
            x = np.frombuffer(raw[:-4], dtype).astype(np.float64)  # last 4 bytes: CRC32C
            e += float(x @ x)
        energy.append(e)
    first = 0
    for ring in rings:
        theta, count = ring["theta_deg"], ring["count"]
        s = sum(sse[v] for v in range(first, first + count))
        e = sum(energy[first : first + count])
        print(f"theta {theta:5.1f}°  {count:3d} slots  rel. error {np.sqrt(s / e):.4f}")
        first += count
    print(f"all                  rel. error {np.sqrt(sum(sse.values()) / sum(energy)):.4f}")


if __name__ == "__main__":
    main()
