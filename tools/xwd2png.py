#!/usr/bin/env python3
"""Converts an XWD screen dump (32-bit ZPixmap, as `xwd` writes for Xvfb's 24-bit
screens) to PNG: `xwd2png.py IN.xwd OUT.png`. Needs Pillow."""
import struct
import sys

from PIL import Image


def main(src: str, dst: str) -> None:
    b = open(src, "rb").read()
    f = struct.unpack(">25I", b[:100])
    header, fmt, w, h = f[0], f[2], f[4], f[5]
    byte_order, bpp, line = f[7], f[11], f[12]
    masks, ncolors = f[14:17], f[19]
    if (fmt, bpp) != (2, 32):
        sys.exit(f"{src}: not a 32-bit ZPixmap (format {fmt}, {bpp} bits per pixel)")
    data = b[header + 12 * ncolors:]
    order = "<I" if byte_order == 0 else ">I"
    rgb = bytearray(w * h * 3)
    for y in range(h):
        row = data[y * line:(y + 1) * line]
        for x in range(w):
            (v,) = struct.unpack_from(order, row, 4 * x)
            for k, m in enumerate(masks):
                shift = (m & -m).bit_length() - 1
                rgb[3 * (y * w + x) + k] = (v & m) >> shift
    Image.frombytes("RGB", (w, h), bytes(rgb)).save(dst)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
