#!/usr/bin/env python3
"""Issue #24: `btf compress -c 16` per kernel path against scikit-learn's PCA, same run.

Usage (normally through benches/isa_sklearn.sh): isa_sklearn.py STORE.btf [K] [OUT_DIR]

1. Prints the CPU model, its flags and /proc/loadavg.
2. For each round and each kernel path the CPU runs (scalar, avx2, avx512; `neon` on
   aarch64), interleaved: `BTF_SIMD=PATH /usr/bin/time -v btf compress STORE -c 16 -o
   OUT --json` (plus COMPRESS_ARGS, e.g. "--codec none") to a fresh output path: wall,
   user and sys seconds and peak RSS from GNU time, the JSON's `seconds`, `simd` (checked to be PATH), `rel_rmse`, and the relative
   RMSE over the K exported slots (from the JSON's per-slot `sse_stored` and `energy`).
3. Exports K view slots with `btf export --format npy --slot J` (lights x h*w*3 float32;
   the f16 values widened exactly, so both sides see the same numbers) and times
   scikit-learn's `PCA(n_components=16, svd_solver=...)` for "randomized" and "full" on
   each slot, `fit_transform` only (loading excluded; one untimed warm-up fit first). That is the decomposition `btf
   compress` does: the rows are the slot's light images, centred on their mean image
   (btf-core/src/pca.rs, `G = X~X~^T` with `X~ = X - 1 mu^T`), 16 components kept. The
   times are extrapolated to every view slot of the store (x n_views / K).
4. Like for like, on the same exported slots in memory: btf-core's `fit_slots` example
   (`FIT_SLOTS`, default $CARGO_TARGET_DIR/release/examples/fit_slots; the .sh wrapper
   builds it) fits every slot on two threads per path, ROUNDS times, right before
   scikit-learn's fits: the per-slot PCA of `btf compress` with nothing read or written,
   timed as scikit-learn's fits are, extrapolated the same way.
5. Prints two markdown tables with ratios. End to end: each path against the fastest path
   and against scikit-learn, wall time of ours (all slots, reading and writing included)
   against the extrapolated fit time of scikit-learn (BLAS threads: its own default, both
   cores here). Fit only: each path's fits against scikit-learn's.

The last line is the whole result as JSON.
"""
import json, os, re, shutil, subprocess, sys, time
from pathlib import Path


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, text=True, capture_output=True, **kw)


def cpu_info():
    model, flags, arch = "?", [], os.uname().machine
    for line in open("/proc/cpuinfo"):
        k, _, v = line.partition(":")
        k = k.strip()
        if k in ("model name", "Model", "CPU part") and model == "?":
            model = v.strip()
        if k in ("flags", "Features") and not flags:
            flags = v.split()
    return model, flags, arch


def loadavg():
    return open("/proc/loadavg").read().strip()


def paths_of(flags, arch):
    """What btf_core::simd::Isa::supported says, from /proc/cpuinfo's spelling."""
    f = set(flags)
    if arch == "aarch64":
        return ["scalar", "neon"]
    out = ["scalar"]
    if {"avx2", "fma", "f16c"} <= f:
        out.append("avx2")
        if "avx512f" in f:
            out.append("avx512")
    return out


def gnu_time(path):
    t = Path(path).read_text()

    def grab(label):
        m = re.search(re.escape(label) + r":\s*(.+)", t)
        return m.group(1).strip() if m else None

    wall = grab("Elapsed (wall clock) time (h:mm:ss or m:ss)")
    secs = 0.0
    for part in wall.split(":"):
        secs = secs * 60 + float(part)
    return {
        "wall_s": secs,
        "user_s": float(grab("User time (seconds)")),
        "sys_s": float(grab("System time (seconds)")),
        "peak_rss_mb": int(grab("Maximum resident set size (kbytes)")) / 1024,
        "cpu_percent": grab("Percent of CPU this job got"),
    }


def spread(n_views, k):
    if n_views == 81 and k == 9:
        return [0, 5, 12, 20, 30, 40, 50, 65, 80]  # one or two per ring of ubo81
    k = min(k, n_views)
    return sorted({round(i * (n_views - 1) / max(k - 1, 1)) for i in range(k)})


def sklearn_fits(slot_files, c):
    import numpy as np
    from sklearn.decomposition import PCA

    info = {}
    try:
        from threadpoolctl import threadpool_info

        info["blas"] = [
            f"{i.get('internal_api')} {i.get('num_threads')} threads {i.get('architecture')}"
            for i in threadpool_info()
        ]
    except Exception:
        pass
    out = {}
    for solver in ("randomized", "full"):
        # One untimed fit first: imports, BLAS thread start-up and first-call costs.
        PCA(n_components=c, svd_solver=solver, random_state=0).fit_transform(np.load(slot_files[0]))
        secs, cpu, sse, energy, per = 0.0, 0.0, 0.0, 0.0, []
        for f in slot_files:
            x = np.load(f)
            t0, c0 = time.perf_counter(), time.process_time()
            p = PCA(n_components=c, svd_solver=solver, random_state=0)
            w = p.fit_transform(x)
            dt = time.perf_counter() - t0
            cpu += time.process_time() - c0
            secs += dt
            per.append(dt)
            rec = p.inverse_transform(w)
            x64 = x.astype(np.float64)
            sse += float(((x64 - rec) ** 2).sum())
            energy += float((x64**2).sum())
        out[solver] = {
            "seconds": secs,
            "cpu_seconds": cpu,
            "per_slot_s": per,
            "rel_rmse": (sse / energy) ** 0.5,
        }
    out.update(info)
    return out


def main():
    args = sys.argv[1:]
    if not args or args[0] in ("-h", "--help"):
        sys.exit(__doc__)
    store = Path(args[0]).resolve()
    k = int(args[1]) if len(args) > 1 else 9
    out = Path(args[2] if len(args) > 2 else f"/tmp/isa_sklearn.{os.getpid()}").resolve()
    out.mkdir(parents=True, exist_ok=True)
    tgt = os.environ.get("CARGO_TARGET_DIR", "target")
    btf = os.environ.get("BTF", f"{tgt}/release/btf")
    rounds = int(os.environ.get("ROUNDS", "1"))
    extra = os.environ.get("COMPRESS_ARGS", "").split()

    model, flags, arch = cpu_info()
    print(f"CPU: {model} ({arch}, {os.cpu_count()} logical CPUs)")
    print("flags:", " ".join(flags))
    simd_flags = [f for f in flags if f.startswith(("avx", "fma", "f16c", "sse4", "asimd"))]
    print("SIMD flags:", " ".join(simd_flags))
    print("loadavg at start:", loadavg())
    paths = os.environ.get("PATHS", "").split() or paths_of(flags, arch)
    print("paths:", " ".join(paths))
    if extra:
        print("btf compress arguments added:", " ".join(extra))

    meta = json.loads(sh([btf, "inspect", str(store), "--json"]).stdout)
    n_views = meta["n_views"]
    print(
        f"store: {store} ({meta['dtype']}, {n_views} views x {meta['n_lights']} lights, "
        f"{meta['width']}x{meta['height']})"
    )
    if meta["dtype"] != "f16":
        conv = Path(tgt) / "release/examples/convert_store"
        if not conv.exists():
            sys.exit(f"{store} is {meta['dtype']}: give an f16 store, or build {conv}")
        f16 = out / (store.stem + "_f16.btf")
        if not f16.exists():
            sh([str(conv), str(store), str(f16), "f16"])
        store = f16
        print(f"converted to f16: {store}")
    slots = spread(n_views, k)

    runs = {p: [] for p in paths}
    for r in range(rounds):
        for p in paths:
            eig, tfile = out / f"out-{p}.eig", out / f"time-{p}-r{r}.txt"
            shutil.rmtree(eig, ignore_errors=True)
            subprocess.run(["sync"], check=False)
            la = loadavg()
            env = dict(os.environ, BTF_SIMD=p, BTF_NO_PROGRESS="1")
            res = sh(
                ["/usr/bin/time", "-v", "-o", str(tfile), btf, "compress", str(store), "-c", "16",
                 "-o", str(eig), "--json"] + extra,
                env=env,
            )
            js = json.loads(res.stdout[res.stdout.index("{"):])
            (out / f"compress-{p}-r{r}.json").write_text(res.stdout)
            if js.get("simd") != p:
                sys.exit(f"BTF_SIMD={p} but the JSON says simd={js.get('simd')}")
            by = {s["view"]: s for s in js["slots"]}
            sse = sum(by[j]["sse_stored"] for j in slots)
            energy = sum(by[j]["energy"] for j in slots)
            run = dict(gnu_time(tfile), loadavg_before=la, json_seconds=js["seconds"],
                       rel_rmse=js["rel_rmse"], rel_rmse_slots=(sse / energy) ** 0.5)
            runs[p].append(run)
            shutil.rmtree(eig, ignore_errors=True)
            print(
                f"round {r + 1} {p}: wall {run['wall_s']:.2f} s, user {run['user_s']:.2f} s, "
                f"sys {run['sys_s']:.2f} s, peak {run['peak_rss_mb']:.0f} MB, "
                f"JSON {run['json_seconds']:.3f} s, rel_rmse {run['rel_rmse']:.15f} "
                f"(load before: {la})"
            )

    slot_dir = out / "slots"
    slot_dir.mkdir(exist_ok=True)
    files = []
    for j in slots:
        f = slot_dir / f"slot{j}.npy"
        sh([btf, "export", str(store), "--format", "npy", "--slot", str(j), "-o", str(f)])
        files.append(f)
    fit_bin = os.environ.get("FIT_SLOTS", f"{tgt}/release/examples/fit_slots")
    if not Path(fit_bin).exists():
        sys.exit(f"{fit_bin} is missing: cargo build --release -p btf-core --example fit_slots")
    fits = {p: [] for p in paths}
    for r in range(rounds):
        res = sh([fit_bin, ",".join(paths)] + [str(f) for f in files])
        for line in res.stdout.splitlines():
            js = json.loads(line)
            fits[js["path"]].append(js)
            print(f"fit round {r + 1} {js['path']}: {js['fits']} fits in {js['wall_s']:.3f} s "
                  f"on two threads, rel_rmse {js['rel_rmse']:.15f}")
    la_sk = loadavg()
    sk = sklearn_fits(files, 16)
    shutil.rmtree(slot_dir, ignore_errors=True)
    scale = n_views / len(slots)
    for s in ("randomized", "full"):
        sk[s]["all_slots_s"] = sk[s]["seconds"] * scale
    print(f"scikit-learn on slots {slots} (load before: {la_sk}); BLAS: {sk.get('blas')}")

    def median(xs):
        xs = sorted(xs)
        return xs[len(xs) // 2] if len(xs) % 2 else 0.5 * (xs[len(xs) // 2 - 1] + xs[len(xs) // 2])

    med = {p: {key: median([r[key] for r in runs[p]]) for key in
               ("wall_s", "user_s", "sys_s", "peak_rss_mb", "json_seconds")} for p in paths}
    fastest = min(med[p]["wall_s"] for p in paths)
    rnd, full = sk["randomized"]["all_slots_s"], sk["full"]["all_slots_s"]
    print()
    print(f"{n_views} view slots, c = 16, f16 store, {meta['width']}x{meta['height']}; "
          f"median of {rounds} round(s); scikit-learn: fit time on {len(slots)} slots x {scale:.2f}")
    print()
    print("| | wall s | user s | sys s | peak RSS MB | x fastest path | sklearn randomized / this "
          "| sklearn full / this | rel. RMSE (all slots) | rel. RMSE (the K slots) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for p in paths:
        m = med[p]
        print(
            f"| btf `BTF_SIMD={p}` | {m['wall_s']:.2f} | {m['user_s']:.2f} | {m['sys_s']:.2f} | "
            f"{m['peak_rss_mb']:.0f} | {m['wall_s'] / fastest:.2f} | {rnd / m['wall_s']:.1f} | "
            f"{full / m['wall_s']:.1f} | {runs[p][0]['rel_rmse']:.9e} | {runs[p][0]['rel_rmse_slots']:.9e} |"
        )
    for s in ("randomized", "full"):
        d = sk[s]
        print(
            f"| scikit-learn `{s}` (extrapolated) | {d['all_slots_s']:.2f} | {d['cpu_seconds'] * scale:.2f} (CPU) | | "
            f"| {d['all_slots_s'] / fastest:.2f} | | | | {d['rel_rmse']:.9e} |"
        )
    print()
    print(f"Fit only, the same {len(slots)} exported slots in memory on both sides (ours: "
          f"2 x {len(slots)} fits on two threads, median of {rounds} round(s); both x {n_views} "
          f"slots):")
    print()
    print("| | seconds (all slots) | sklearn randomized / this | sklearn full / this "
          "| rel. RMSE (the K slots) |")
    print("|---|---:|---:|---:|---:|")
    for p in paths:
        t = median([f["wall_s"] for f in fits[p]]) / (2 * len(slots)) * n_views
        print(f"| `fit_slots` {p} | {t:.2f} | {rnd / t:.1f} | {full / t:.1f} | "
              f"{fits[p][0]['rel_rmse']:.9e} |")
    for s in ("randomized", "full"):
        d = sk[s]
        print(f"| scikit-learn `{s}` | {d['all_slots_s']:.2f} | | | {d['rel_rmse']:.9e} |")
    print()
    print("loadavg at end:", loadavg())
    print(json.dumps({"cpu": model, "arch": arch, "paths": paths, "store": str(store),
                      "meta": meta, "slots": slots, "runs": runs, "fits": fits,
                      "sklearn": sk}))


if __name__ == "__main__":
    main()
