#!/usr/bin/env python3
"""Independent check of `btf knit ref` against Mitsuba 3 (issue 18; not a CI test).

The same explicit fibers (a stockinette patch of `fine-2ply`, no hairs, written by
`btf knit fibers` as Mitsuba curve text) are rendered by Mitsuba 3's `linearcurve` shape with
a `diffuse` BSDF and by `btf knit ref --shading lambert` (capsule chains, Lambert surface
BRDF), under the same directional light, pinhole camera and bounce count, no wrap, no
backing. Both images are box-filtered pixel averages. Reports the relative RMSE
sqrt(sum (a-b)^2 / sum b^2) over all pixels and over pixels both renders cover, plus the
noise floor (the same estimate between two Mitsuba seeds).

Usage: pip install mitsuba numpy; python3 benches/mitsuba_crosscheck.py [--btf PATH]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np


def rel_rmse(a, b, mask=None):
    if mask is not None:
        a, b = a[mask], b[mask]
    return float(math.sqrt(((a - b) ** 2).sum() / max((b ** 2).sum(), 1e-30)))


def read_exr(path):
    import mitsuba as mi
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--btf", default=os.path.join(os.path.dirname(__file__), "..", "target", "release", "btf"))
    ap.add_argument("--size", default="128,96")
    ap.add_argument("--spp-ours", type=int, default=64)
    ap.add_argument("--spp-mitsuba", type=int, default=256)
    ap.add_argument("--bounces", type=int, default=3)
    ap.add_argument("--chart", default="stockinette")
    ap.add_argument("--yarn", default="fine-2ply")
    ap.add_argument("--block", type=int, default=8,
                    help="also compare block averages of BLOCK x BLOCK pixels (the fibers are "
                         "sub-pixel, so single pixels are coverage-noise dominated)")
    args = ap.parse_args()
    btf = args.btf if os.path.exists(args.btf) else args.btf.replace("release", "debug")
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    w, h = (int(x) for x in args.size.split(","))
    tmp = tempfile.mkdtemp(prefix="mitsuba-xcheck-")
    fibers_m = os.path.join(tmp, "fibers.txt")
    env = dict(os.environ, BTF_NO_PROGRESS="1")
    subprocess.run([btf, "knit", "fibers", "--chart", args.chart, "--yarn", args.yarn, "--no-hairs",
                    "-o", fibers_m], check=True, env=env)
    # Mitsuba gets millimetres (its float32 kernels and a 5 µm radius); radiance under a
    # directional light does not depend on the scale.
    fibers_mm = os.path.join(tmp, "fibers_mm.txt")
    pts = []
    with open(fibers_m) as f, open(fibers_mm, "w") as g:
        for line in f:
            if line.strip():
                v = [float(x) * 1000.0 for x in line.split()]
                pts.append(v[:3])
                g.write("%.9g %.9g %.9g %.9g\n" % tuple(v))
            else:
                g.write("\n")
    p = np.array(pts)
    lo, hi = p.min(0), p.max(0)
    c = 0.5 * (lo + hi)
    eye = c + np.array([0.0, -0.9, 1.3]) * (hi - lo).max()
    fov = 40.0
    light_theta, light_phi = 35.0, 60.0
    t, ph = math.radians(light_theta), math.radians(light_phi)
    to_light = [math.sin(t) * math.cos(ph), math.sin(t) * math.sin(ph), math.cos(t)]
    # Ours: metres.
    ours = os.path.join(tmp, "ours.exr")
    ours2 = os.path.join(tmp, "ours_seed2.exr")
    cam = "persp:" + ",".join("%.9g" % (x / 1000.0) for x in list(eye) + list(c)) + ",%g" % fov
    def run_ours(path, seed):
        return subprocess.run([btf, "knit", "ref", "--chart", args.chart, "--yarn", args.yarn, "--no-hairs",
                               "--no-wrap", "--no-backing", "--shading", "lambert", "--albedo", "0.8,0.8,0.8",
                               "--camera", cam, "--light", "dir:%g,%g,1" % (light_theta, light_phi),
                               "--bounces", str(args.bounces), "--size", args.size, "--spp", str(args.spp_ours),
                               "--render-seed", str(seed), "--json", "-i", path],
                              check=True, env=env, capture_output=True, text=True)
    r = run_ours(ours, 1)
    run_ours(ours2, 7)
    summary = json.loads(r.stdout)

    def render_mitsuba(seed):
        scene = mi.load_dict({
            "type": "scene",
            "integrator": {"type": "path", "max_depth": args.bounces + 1, "rr_depth": 1000},
            "sensor": {
                "type": "perspective", "fov": fov, "fov_axis": "y",
                "to_world": mi.ScalarTransform4f().look_at(origin=list(eye), target=list(c), up=[0, 0, 1]),
                "sampler": {"type": "independent", "sample_count": args.spp_mitsuba, "seed": seed},
                "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"},
                         "pixel_format": "rgb"},
            },
            "fibers": {"type": "linearcurve", "filename": fibers_mm,
                       "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}}},
            "sun": {"type": "directional", "direction": [-x for x in to_light],
                    "irradiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
        })
        return np.array(mi.render(scene), dtype=np.float64)[..., :3]

    m1 = render_mitsuba(1)
    m2 = render_mitsuba(2)
    a = read_exr(ours)
    # Mitsuba's image x may run the other way from ours: report which orientation matched.
    cands = {"as is": a, "mirrored in x": a[:, ::-1]}
    best = min(cands, key=lambda k: rel_rmse(cands[k], m1))
    a = cands[best]
    a2 = read_exr(ours2)
    if best != "as is":
        a2 = a2[:, ::-1]
    k = args.block

    def blocks(x):
        hh, ww = (x.shape[0] // k) * k, (x.shape[1] // k) * k
        return x[:hh, :ww].reshape(hh // k, k, ww // k, k, 3).mean(axis=(1, 3))

    ab, mb, mb2, ab2 = blocks(a), blocks(m1), blocks(m2), blocks(a2)
    e_b = rel_rmse(ab, mb)
    floor_b = math.sqrt(rel_rmse(mb2, mb) ** 2 / 2 + rel_rmse(ab2, ab) ** 2 / 2)
    mask = (a.sum(-1) > 0) & (m1.sum(-1) > 0)
    out = {
        "fibers": summary["fibers"], "segments": summary["segments"],
        "ours_spp": args.spp_ours, "mitsuba_spp": args.spp_mitsuba, "bounces": args.bounces,
        "orientation": best,
        "rel_rmse_all": rel_rmse(a, m1), "rel_rmse_covered": rel_rmse(a, m1, mask),
        "noise_floor_mitsuba_seeds": rel_rmse(m2, m1),
        "noise_floor_ours_seeds": rel_rmse(a2, a),
        "block": k,
        "rel_rmse_blocks": e_b,
        "noise_floor_blocks": floor_b,
        "bias_estimate_blocks": math.sqrt(max(0.0, e_b ** 2 - floor_b ** 2)),
        "mean_ours": float(a.mean()), "mean_mitsuba": float(m1.mean()),
        "coverage_ours": float((a.sum(-1) > 0).mean()), "coverage_mitsuba": float((m1.sum(-1) > 0).mean()),
        "ours_rays_per_second": summary["rays_per_second"],
        "target": 0.03, "workdir": tmp,
    }
    print(json.dumps(out, indent=2))
    return 0 if out["rel_rmse_blocks"] <= 0.03 else 1


if __name__ == "__main__":
    sys.exit(main())
