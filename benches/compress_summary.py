#!/usr/bin/env python3
"""Summarises a compression report (`btf compress --json` or the btf-core example
`compress_store`): wall seconds, whole-BTF relative RMSE, and the relative RMSE over the
given view slots (to compare with benches/sklearn_baseline.py on the same slots).

Usage: python3 benches/compress_summary.py REPORT.json [J ...]
"""
import json, sys

r = json.load(open(sys.argv[1]))
slots = [int(j) for j in sys.argv[2:]]
out = {"seconds": r["seconds"], "rel_rmse": r["rel_rmse"], "rel_rmse_exact": r["rel_rmse_exact"]}
if slots:
    by = {s["view"]: s for s in r["slots"]}
    sse = sum(by[j]["sse_stored"] for j in slots)
    sse_exact = sum(by[j]["sse"] for j in slots)
    energy = sum(by[j]["energy"] for j in slots)
    out["slots"] = slots
    out["rel_rmse_slots"] = (sse / energy) ** 0.5
    out["rel_rmse_exact_slots"] = (sse_exact / energy) ** 0.5
    ey = max(abs(s["sse"] - s["discarded_eigen_sum"]) / s["discarded_eigen_sum"] for s in r["slots"] if s["discarded_eigen_sum"] > 0)
    out["eckart_young_max_rel"] = ey
print(json.dumps(out))
