"""Writes the blosc1 fixture frames of btf-core's blosc reader tests with c-blosc itself.

Usage: python3 make_frames.py   (numcodecs 0.16.6, which bundles c-blosc 1.21; run here)

Each case NAME gives NAME.raw.zst (the data, as a zstd frame: numcodecs.Zstd level 19,
to keep the fixtures small) and NAME.blosc (numcodecs.blosc.compress of it,
zstd, one thread). Blocksizes are small so that every frame has several blocks and a
leftover one. Split frames are made in a child process with BLOSC_SPLITMODE=ALWAYS
(c-blosc reads the variable once, globally); the script checks the flag it expects.
"""
import os
import subprocess
import sys

import numpy as np

# name: (bytes, typesize, clevel, shuffle, blocksize, split)
CASES = {
    "f16_shuffle": (3002, 2, 1, 1, 1024, False),
    "f16_noshuffle": (3002, 2, 3, 0, 1024, False),
    # Splitting c-blosc enlarges the blocksize to 64 KiB at least: larger buffers.
    "f16_shuffle_split": (70_002, 2, 1, 1, 1024, True),
    "u32_shuffle_split_odd": (70_001, 4, 5, 1, 1024, True),
    "f64_noshuffle_odd": (2999, 8, 1, 0, 1024, False),
    "u8_shuffle": (2000, 1, 1, 1, 512, False),
    "small_memcpyed": (100, 2, 1, 1, 0, False),
    "clevel0_memcpyed": (1000, 2, 0, 1, 0, False),
}


def data(n, typesize):
    """Smooth high bytes, noisy low bytes: like f16 images."""
    rng = np.random.default_rng(n * 31 + typesize)
    x = np.linspace(0.0, 4.0, (n + 1) // 2)
    v = (np.sin(x) + 1.5 + rng.normal(0, 0.002, x.size)).astype("<f2").view(np.uint8)
    return v[:n].tobytes()


def make(split):
    from numcodecs import Zstd, blosc

    # The global (threaded) entry point is the one that reads BLOSC_SPLITMODE.
    blosc.use_threads = split
    blosc.set_nthreads(1)
    for name, (n, ts, clevel, shuffle, bs, want_split) in CASES.items():
        if want_split != split:
            continue
        raw = data(n, ts)
        frame = blosc.compress(raw, b"zstd", clevel, shuffle, bs, typesize=ts)
        assert blosc.decompress(frame) == raw
        memcpyed = frame[2] & 0x02
        if not memcpyed:
            assert bool(frame[2] & 0x10) != split, (name, frame[2])
        with open(f"{name}.raw.zst", "wb") as f:
            f.write(Zstd(level=19).encode(raw))
        with open(f"{name}.blosc", "wb") as f:
            f.write(frame)
        print(name, n, "->", len(frame), "flags", hex(frame[2]), "blocksize",
              int.from_bytes(frame[8:12], "little"))


if __name__ == "__main__":
    os.chdir(os.path.dirname(os.path.abspath(__file__)))
    if sys.argv[1:] == ["split"]:
        make(True)
    else:
        make(False)
        env = dict(os.environ, BLOSC_SPLITMODE="ALWAYS")
        subprocess.run([sys.executable, __file__, "split"], env=env, check=True)
