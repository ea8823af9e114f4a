#!/usr/bin/env python3
"""Exports view slots of an f32 or f16 BTF store as DIR/slotJ.npy (lights x h*w*3 float32),
the same arrays as `btf export --format npy`, by reading the Zarr chunks directly (each
chunk is the little-endian image followed by its 4-byte CRC32C; f16 values are widened to
f32 exactly), so the baseline needs no build of the CLI.

Usage: python3 benches/export_slots_npy.py STORE.btf DIR J [J ...]
"""
import json, sys, numpy as np
store, out, slots = sys.argv[1], sys.argv[2], [int(s) for s in sys.argv[3:]]
meta = json.load(open(f"{store}/normtextures/zarr.json"))
nv, nl, h, w, ch = meta["shape"]
dtype = {"float32": "<f4", "float16": "<f2"}[meta["data_type"]]
for j in slots:
    x = np.empty((nl, h * w * ch), np.float32)
    for l in range(nl):
        raw = open(f"{store}/normtextures/c/{j}/{l}/0/0/0", "rb").read()
        x[l] = np.frombuffer(raw[:-4], dtype).astype(np.float32)
    np.save(f"{out}/slot{j}.npy", x)
    print(j, x.shape, float(x.mean()))
