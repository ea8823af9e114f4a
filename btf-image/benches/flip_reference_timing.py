"""Baseline for btf-image/benches/flip.rs: NVIDIA's flip_evaluator (C++/OpenMP) on the
same 512² pair (the same reference; the test's noise comes from numpy, which does not
change the work). Prints the median of 10 runs per case, seconds.

    python3 -m pip install flip-evaluator
    python3 btf-image/benches/flip_reference_timing.py
"""
import time

import flip_evaluator as fl
import numpy as np

N = 512


def pair(peak):
    x, y = np.meshgrid(np.arange(N) / N, np.arange(N) / N)
    shade = np.maximum(1.0 - np.hypot(x - 0.4, y - 0.5), 0.0) ** 3
    weave = 0.75 + 0.25 * np.sin(x * 180.0) * np.cos(y * 180.0)
    ref = peak * (shade * weave)[:, :, None] * np.array([0.9, 0.6, 0.4])
    noise = np.random.default_rng(1).random(ref.shape)
    return ref.astype(np.float32), (ref * (0.6 + 0.8 * noise)).astype(np.float32)


for name, peak, rng in [("flip_ldr 512²", 1.0, "LDR"), ("flip_hdr 512²", 20.0, "HDR")]:
    r, t = pair(peak)
    times = []
    for _ in range(10):
        t0 = time.perf_counter()
        _, mean, params = fl.evaluate(r, t, rng, inputsRGB=False, applyMagma=False)
        times.append(time.perf_counter() - t0)
    n = params["numExposures"] if rng == "HDR" else 1
    print(f"{name} ({n} exposures): median {np.median(times) * 1e3:.1f} ms, mean FLIP {mean:.4f}")
