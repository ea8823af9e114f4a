"""Read a btf toolkit store with zarr-python (>= 3) and numpy only.

Usage: python3 stores_example.py MATERIAL.eig VIEW_SLOT LIGHT OUT.npy [MATERIAL.btf]

Rebuilds the texture of view slot VIEW_SLOT under light LIGHT from the eigen store,
saves it as OUT.npy (float32, [y][x][rgb]) and prints the slot's and light's directions.
With a BTF store as well, prints how far the rebuilt texture is from the measured one.
"""
import sys

import numpy as np
import zarr

eig_path, j, i, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
g = zarr.open_group(eig_path, mode="r")
meta = g.attrs["btf"]
print("kind:", meta["kind"], "| size:", meta["width"], "x", meta["height"],
      "| components:", g.attrs["eigen"]["components"])

# Directions: degrees, tangent frame (+z normal, +x along u, theta from +z, phi from +x to +y).
view_theta, view_phi = g["view_theta_deg"][:], g["view_phi_deg"][:]
light_theta, light_phi = g["light_theta_deg"][:], g["light_phi_deg"][:]
print(f"view slot {j}: theta={view_theta[j]:g} deg, phi={view_phi[j]:g} deg")
print(f"light {i}: theta={light_theta[i]:g} deg, phi={light_phi[i]:g} deg")

# T = mean + sum_k p_ik * B_k, with B_k = stored * scale + offset (scale_offset[j, k]).
mean = g["mean"][j].astype(np.float64)                 # (y, x, 3)
stored = g["eigentextures"][j].astype(np.float64)      # (c, y, x, 3), f16 or u8
scale_offset = g["scale_offset"][j].astype(np.float64)  # (c, 2)
basis = stored * scale_offset[:, 0, None, None, None] + scale_offset[:, 1, None, None, None]
weights = g["weights"][j, i].astype(np.float64)        # (c,)
texture = mean + np.tensordot(weights, basis, axes=1)
np.save(out, texture.astype("<f4"))
print("rebuilt texture: shape", texture.shape, "mean value", float(texture.mean()))

if len(sys.argv) > 5:
    b = zarr.open_group(sys.argv[5], mode="r")
    measured = b["normtextures"][j, i].astype(np.float64)  # (y, x, 3)
    rel = np.sqrt(np.mean((texture - measured) ** 2) / np.mean(measured ** 2))
    print(f"relative RMS difference to the measured image: {rel:.3g}")
