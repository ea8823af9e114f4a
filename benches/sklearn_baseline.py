#!/usr/bin/env python3
"""Baseline for the compression benchmark: scikit-learn's PCA on the same view slots.

Usage: python3 benches/sklearn_baseline.py DIR_WITH_slot*.npy [--components 16] [--solvers randomized,full]

Each `slotJ.npy` is one view slot as exported by `btf export --format npy` (lights x
(h*w*3) float32). For every solver, prints the seconds per slot and the relative RMSE
||X - X_hat|| / ||X|| over all slots, as JSON on the last line.
"""
import glob, json, sys, time

import numpy as np
from sklearn.decomposition import PCA


def main():
    d = sys.argv[1]
    c = int(sys.argv[sys.argv.index("--components") + 1]) if "--components" in sys.argv else 16
    solvers = (sys.argv[sys.argv.index("--solvers") + 1] if "--solvers" in sys.argv else "randomized,full").split(",")
    files = sorted(glob.glob(f"{d}/slot*.npy"))
    if not files:
        sys.exit(f"no slot*.npy in {d}")
    out = {"slots": len(files), "components": c}
    try:
        from threadpoolctl import threadpool_info
        out["blas"] = [(i.get("internal_api"), i.get("num_threads"), i.get("architecture")) for i in threadpool_info()]
    except Exception:
        pass
    for solver in solvers:
        secs, sse, energy = 0.0, 0.0, 0.0
        for f in files:
            x = np.load(f)
            t0 = time.perf_counter()
            p = PCA(n_components=c, svd_solver=solver, random_state=0)
            w = p.fit_transform(x)
            secs += time.perf_counter() - t0
            rec = p.inverse_transform(w)
            sse += float(((x.astype(np.float64) - rec) ** 2).sum())
            energy += float((x.astype(np.float64) ** 2).sum())
        out[solver] = {"seconds_total": secs, "seconds_per_slot": secs / len(files), "rel_rmse": (sse / energy) ** 0.5}
        print(f"{solver}: {secs / len(files):.3f} s/slot, {secs:.2f} s total, rel RMSE {(sse / energy) ** 0.5:.4e}", file=sys.stderr)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
