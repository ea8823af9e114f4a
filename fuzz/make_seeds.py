#!/usr/bin/env python3
"""Writes small, valid seed inputs for every fuzz target under fuzz/seeds/<target>/.

Standard library only (no numpy, PIL, zarr or OpenEXR): every format is written by hand,
following the readers in this repository, so that each seed gets past the header checks
and reaches the decoder. Each seed is a few hundred bytes; run from anywhere:

    python3 fuzz/make_seeds.py          # or: bash fuzz/make_seeds.sh

The layout of an input is the one its target expects (see fuzz/README.md): a leading
selector byte where the target has one, `0xFF` between the files of a multi-file input.
"""

import json
import os
import re
import shutil
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, "seeds")
SEP = b"\xff"


def put(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# --------------------------------------------------------------------------- images


def pixel(x, y, w, h):
    """A small linear RGB test pattern in [0, 1]."""
    return ((x + 0.5) / w, (y + 0.5) / h, 0.25 + 0.5 * ((x + y) % 2))


def png(w, h, depth=8, colour=2):
    """PNG: colour type 2 (RGB) or 0 (grey), 8 or 16 bits, filter 0."""
    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", zlib.crc32(tag + body))
    raw = bytearray()
    for y in range(h):
        raw.append(0)
        for x in range(w):
            r, g, b = pixel(x, y, w, h)
            vals = (r, g, b) if colour == 2 else ((r + g + b) / 3,)
            for v in vals:
                if depth == 8:
                    raw.append(int(v * 255))
                else:
                    raw += struct.pack(">H", int(v * 4095) << 4)  # 12-bit DN, left-aligned
    ihdr = struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
            + chunk(b"IEND", b""))


def tiff(w, h, bits=8):
    """Little-endian baseline TIFF, RGB, uncompressed, one strip."""
    data = bytearray()
    for y in range(h):
        for x in range(w):
            for v in pixel(x, y, w, h):
                data += bytes([int(v * 255)]) if bits == 8 else struct.pack("<H", int(v * 4095) << 4)
    header = 8
    bps_off = header
    strip_off = bps_off + 6
    ifd_off = strip_off + len(data)
    ifd_off += ifd_off % 2
    tags = [
        (256, 3, 1, w), (257, 3, 1, h), (258, 3, 3, bps_off), (259, 3, 1, 1), (262, 3, 1, 2),
        (273, 4, 1, strip_off), (277, 3, 1, 3), (278, 3, 1, h), (279, 4, 1, len(data)),
        (284, 3, 1, 1),
    ]
    out = bytearray(b"II*\x00" + struct.pack("<I", ifd_off))
    out += struct.pack("<HHH", bits, bits, bits)
    out += data
    while len(out) < ifd_off:
        out.append(0)
    out += struct.pack("<H", len(tags))
    for tag, typ, count, value in tags:
        if typ == 3 and count == 1:
            out += struct.pack("<HHIHH", tag, typ, count, value, 0)
        else:
            out += struct.pack("<HHII", tag, typ, count, value)
    out += struct.pack("<I", 0)
    return bytes(out)


def bmp(w, h):
    """24-bit BI_RGB BMP, bottom-up rows padded to 4 bytes."""
    row = (w * 3 + 3) & ~3
    pix = bytearray()
    for y in reversed(range(h)):
        line = bytearray()
        for x in range(w):
            r, g, b = pixel(x, y, w, h)
            line += bytes([int(b * 255), int(g * 255), int(r * 255)])
        pix += line + b"\x00" * (row - len(line))
    info = struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, len(pix), 2835, 2835, 0, 0)
    head = b"BM" + struct.pack("<IHHI", 14 + len(info) + len(pix), 0, 0, 14 + len(info))
    return head + info + bytes(pix)


def rgbe(r, g, b):
    import math
    m = max(r, g, b)
    if m < 1e-32:
        return bytes([0, 0, 0, 0])
    mant, e = math.frexp(m)
    s = mant * 256.0 / m
    return bytes([int(r * s), int(g * s), int(b * s), e + 128])


def hdr(w, h, rle):
    """Radiance RGBE: flat pixels, or the new run-length scanlines (8 <= w < 32768)."""
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n")
    out += b"-Y %d +X %d\n" % (h, w)
    for y in range(h):
        line = [rgbe(*[4.0 * v for v in pixel(x, y, w, h)]) for x in range(w)]
        if not rle:
            for p in line:
                out += p
            continue
        out += bytes([2, 2, w >> 8, w & 255])
        for c in range(4):
            vals = [p[c] for p in line]
            i = 0
            while i < w:
                run = 1
                while i + run < w and run < 127 and vals[i + run] == vals[i]:
                    run += 1
                if run > 2:
                    out += bytes([128 + run, vals[i]])
                    i += run
                else:
                    n = min(w - i, 128)
                    out += bytes([n]) + bytes(vals[i:i + n])
                    i += n
    return bytes(out)


def exr(w, h, compression=0, half=False):
    """Scanline OpenEXR, channels B, G, R; compression 0 (none), 2 (ZIPS) or 3 (ZIP)."""
    def attr(name, typ, value):
        return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(value)) + value
    ptype = 1 if half else 2
    chlist = b"".join(c + b"\0" + struct.pack("<iBBBBii", ptype, 0, 0, 0, 0, 1, 1)
                      for c in (b"B", b"G", b"R")) + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    head = (b"\x76\x2f\x31\x01" + struct.pack("<I", 2)
            + attr("channels", "chlist", chlist)
            + attr("compression", "compression", bytes([compression]))
            + attr("dataWindow", "box2i", box)
            + attr("displayWindow", "box2i", box)
            + attr("lineOrder", "lineOrder", b"\0")
            + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
            + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
            + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
            + b"\0")
    lines_per_block = 16 if compression == 3 else 1
    blocks = []
    for y0 in range(0, h, lines_per_block):
        raw = bytearray()
        for y in range(y0, min(h, y0 + lines_per_block)):
            px = [pixel(x, y, w, h) for x in range(w)]
            for c in (2, 1, 0):  # B, G, R
                for p in px:
                    raw += struct.pack("<e" if half else "<f", 2.0 * p[c])
        data = bytes(raw)
        if compression in (2, 3):
            t = data[0::2] + data[1::2]
            d = bytearray(t)
            for i in range(len(t) - 1, 0, -1):
                d[i] = (t[i] - t[i - 1] + 128) & 0xFF
            z = zlib.compress(bytes(d), 9)
            if len(z) < len(data):
                data = z
        blocks.append(struct.pack("<ii", y0, len(data)) + data)
    offsets = bytearray()
    pos = len(head) + 8 * len(blocks)
    for b in blocks:
        offsets += struct.pack("<Q", pos)
        pos += len(b)
    return head + bytes(offsets) + b"".join(blocks)


class Bits:
    def __init__(self):
        self.out = bytearray()
        self.acc = 0
        self.n = 0

    def put(self, code, length):
        for i in reversed(range(length)):
            self.acc = (self.acc << 1) | ((code >> i) & 1)
            self.n += 1
            if self.n == 8:
                self.out.append(self.acc)
                if self.acc == 0xFF:
                    self.out.append(0)  # byte stuffing
                self.acc, self.n = 0, 0

    def flush(self):
        while self.n:
            self.put(1, 1)
        return bytes(self.out)


def jpeg(w, h, components=3):
    """Baseline JPEG, 1x1 sampling, every block flat (DC only): the standard luminance DC
    table and a one-symbol AC table holding just EOB."""
    dc_counts = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0]
    dc_syms = list(range(12))
    codes, code, k = {}, 0, 0
    for length, n in enumerate(dc_counts, 1):
        for _ in range(n):
            codes[dc_syms[k]] = (code, length)
            code += 1
            k += 1
        code <<= 1

    def seg(marker, body):
        return bytes([0xFF, marker]) + struct.pack(">H", len(body) + 2) + body
    out = bytearray(b"\xff\xd8")
    out += seg(0xDB, bytes([0]) + bytes([1] * 64))  # quantisation table 0, all ones
    comps = b"".join(bytes([i + 1, 0x11, 0]) for i in range(components))
    out += seg(0xC0, bytes([8]) + struct.pack(">HH", h, w) + bytes([components]) + comps)
    out += seg(0xC4, bytes([0x00]) + bytes(dc_counts) + bytes(dc_syms))
    out += seg(0xC4, bytes([0x10]) + bytes([1] + [0] * 15) + bytes([0]))
    out += seg(0xDA, bytes([components]) + b"".join(bytes([i + 1, 0x00]) for i in range(components))
               + bytes([0, 63, 0]))
    bits = Bits()
    pred = [0] * components
    for by in range((h + 7) // 8):
        for bx in range((w + 7) // 8):
            for c in range(components):
                level = [40 + 10 * bx + 5 * by, -20, 30][c] if components == 3 else 10 * (bx + by)
                dc = level * 8  # flat block: DC = 8 * (value - 128) with an all-ones table
                diff = dc - pred[c]
                pred[c] = dc
                size = abs(diff).bit_length()
                bits.put(*codes[size])
                if size:
                    bits.put(diff if diff > 0 else diff + (1 << size) - 1, size)
                bits.put(0, 1)  # EOB
    out += bits.flush() + b"\xff\xd9"
    return bytes(out)


# --------------------------------------------------------------------------- Zarr stores


def crc32c(data):
    table = crc32c.table
    if table is None:
        table = []
        for i in range(256):
            c = i
            for _ in range(8):
                c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
            table.append(c)
        crc32c.table = table
    c = 0xFFFFFFFF
    for b in data:
        c = table[(c ^ b) & 0xFF] ^ (c >> 8)
    return c ^ 0xFFFFFFFF


crc32c.table = None

DTYPES = {"float16": ("<e", 2), "float32": ("<f", 4), "float64": ("<d", 8), "uint8": ("<B", 1)}


def array_json(shape, chunk, dtype, names):
    return json.dumps({
        "zarr_format": 3, "node_type": "array", "shape": shape, "data_type": dtype,
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": chunk}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "fill_value": 0 if dtype == "uint8" else 0.0,
        "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}, {"name": "crc32c"}],
        "attributes": {}, "dimension_names": names,
    }, separators=(",", ":")).encode()


def chunk_bytes(chunk, dtype, f=lambda i: 0.25 * (i % 7)):
    fmt, _ = DTYPES[dtype]
    n = 1
    for c in chunk:
        n *= c
    raw = b"".join(struct.pack(fmt, int(f(i) * 40) if dtype == "uint8" else f(i)) for i in range(n))
    return raw + struct.pack("<I", crc32c(raw))


def ring(theta, count, phi=0.0):
    return {"theta_deg": theta, "count": count, "phi_offset_deg": phi}


def btf_meta(kind, views, lights, w, h):
    return {
        "kind": kind,
        "view_sampling": {"name": "custom", "rings": views},
        "light_sampling": {"name": "custom", "rings": lights},
        "width": w, "height": h,
        "color_space": "linear sRGB (Rec. 709 primaries)",
        "units": "radiance per unit irradiance perpendicular to the light (1/sr)",
        "provenance": {"generator": "fuzz/make_seeds.py"},
    }


def group_json(attrs):
    return json.dumps({"zarr_format": 3, "node_type": "group", "attributes": attrs},
                      separators=(",", ":")).encode()


def count(rings):
    return sum(r["count"] for r in rings)


# --------------------------------------------------------------------------- Bonn UBO2014


def u32(v):
    return struct.pack("<I", v)


def f32s(*v):
    return struct.pack("<%df" % len(v), *v)


def scalars(vals, size):
    fmt = {2: "<e", 4: "<f", 8: "<d"}[size]
    return b"".join(struct.pack(fmt, v) for v in vals)


def text(s, n):
    b = s.encode()[:n]
    return b + b"\0" * (n - len(b))


def meta_block(version=4, channels=("R", "G", "B"), xml="<m/>"):
    body = u32(version) + text("fuzz seed", 80) + text("sensor", 80) + text("lamp", 80)
    body += f32s(10.0) + f32s(1.0, 1.0, 1.0)
    if version > 1:
        body += u32(1)
    if version > 2:
        body += u32(len(xml)) + xml.encode()
    if version > 3:
        body += u32(len(channels))
        for c in channels:
            body += u32(len(c)) + c.encode()
    return u32(len(body) + 4) + body


VIEWS = [(0.0, 0.0), (0.5, 1.0)]
LIGHTS = [(0.0, 0.0), (0.6, 2.0)]


def sampling(views=VIEWS, lights=LIGHTS):
    out = u32(len(views))
    for v in views:
        out += f32s(*v) + u32(len(lights))
        for l in lights:
            out += f32s(*l)
    return out


def rotations(n):
    return u32(n) + b"".join(f32s(1, 0, 0, 0, 1, 0, 0, 0, 1) for _ in range(n))


def common_header(rot, w=2, h=2, version=4, views=VIEWS, lights=LIGHTS):
    out = meta_block(version) + sampling(views, lights) + u32(w) + u32(h)
    if rot:
        out += rotations(1)
    return out


def pvf_slots(nv, nl, texels, nc=3, p=1, size=4, light_rows=False):
    out = b""
    for v in range(nv):
        dim, nw = (nc * nl, texels) if light_rows else (nc * texels, nl)
        out += bytes([size]) + u32(p) + u32(nw) + u32(dim)
        out += scalars([1.0 / (k + 1) for k in range(p)], size)
        out += scalars([0.1 * (i % 5) for i in range(dim)], size)
        out += scalars([0.05 * ((i + v) % 3) for i in range(dim * p)], size)
        out += scalars([0.5 - 0.1 * (i % 4) for i in range(nw * p)], size)
    return out


def pvf_after_signature(rot, legacy=False, size=4, light_rows=False, p=1):
    """Bytes that follow `!PVF06FC`/`!PVF06FCR` for a 2×2, 2-view, 2-light RGB file."""
    w = h = 2
    if legacy:
        body = struct.pack("<i", 301074) + u32(p) + u32(w) + u32(h) + u32(len(VIEWS)) + sampling()
    else:
        body = common_header(rot, w, h) + u32(p) + u32(len(VIEWS))
    return body + pvf_slots(len(VIEWS), len(LIGHTS), w * h, 3, p, size, light_rows)


def svd(rows, cols, p=1, size=4):
    return (bytes([size]) + u32(p) + u32(rows) + u32(cols)
            + scalars([1.0] * p, size)
            + scalars([0.1 * (i % 5) for i in range(rows * p)], size)
            + scalars([0.2 * (i % 3) for i in range(cols * p)], size))


# --------------------------------------------------------------------------- targets


def env_seeds():
    for target in ("envmap",):
        put(target, "flat-8x4.hdr", b"\x00" + hdr(8, 4, rle=False))
        put(target, "rle-16x8.hdr", b"\x00" + hdr(16, 8, rle=True))
        put(target, "none-8x4.exr", b"\x01" + exr(8, 4, 0))
        put(target, "zips-half-8x4.exr", b"\x01" + exr(8, 4, 2, half=True))
        put(target, "zip-16x8.exr", b"\x01" + exr(16, 8, 3))


def raw_image_seeds():
    put("raw_image", "rgb8-4x4.png", b"\x00" + png(4, 4, 8, 2))
    put("raw_image", "rgb16-4x4.png", b"\x00" + png(4, 4, 16, 2))
    put("raw_image", "grey16-4x4.png", b"\x00" + png(4, 4, 16, 0))
    put("raw_image", "rgb8-4x4.tiff", b"\x01" + tiff(4, 4, 8))
    put("raw_image", "rgb16-4x4.tiff", b"\x01" + tiff(4, 4, 16))
    put("raw_image", "none-4x4.exr", b"\x02" + exr(4, 4, 0))
    put("raw_image", "zips-4x4.exr", b"\x02" + exr(4, 4, 2, half=True))


def ubo2003_image_seeds():
    put("ubo2003_image", "rgb-16x8.jpg", b"\x00" + jpeg(16, 8, 3))
    put("ubo2003_image", "grey-8x8.jpg", b"\x00" + jpeg(8, 8, 1))
    put("ubo2003_image", "rgb8-4x4.png", b"\x01" + png(4, 4, 8, 2))
    put("ubo2003_image", "rgb-5x3.bmp", b"\x02" + bmp(5, 3))
    put("ubo2003_image", "rle-16x8.hdr", b"\x03" + hdr(16, 8, rle=True))
    put("ubo2003_image", "zips-4x4.exr", b"\x04" + exr(4, 4, 2))


def strip_comments(toml_text):
    lines = []
    for line in toml_text.splitlines():
        if line.lstrip().startswith("#") or not line.strip():
            continue
        lines.append(re.sub(r"\s+#[^\"]*$", "", line))
    return ("\n".join(lines) + "\n").encode()


def scene_seeds():
    d = os.path.join(ROOT, "examples", "scenes")
    for name in ("plane.toml", "sphere-shadows.toml", "curtain-backlit.toml", "shirt-env.toml"):
        with open(os.path.join(d, name)) as f:
            put("scene_toml", name, strip_comments(f.read()))


def obj_seeds():
    quad = (b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
            b"vn 0 0 1\nusemtl cloth\nf 1/1/1 2/2/1 3/3/1 4/4/1\n")
    put("obj_mesh", "quad-uv-normal.obj", b"\x00" + quad)
    cube = bytearray(b"# unit cube, no uvs (planar projection), negative indices\no cube\n")
    for x in (0, 1):
        for y in (0, 1):
            for z in (0, 1):
                cube += b"v %d %d %d\n" % (x, y, z)
    cube += (b"g sides\nusemtl a\nf 1 2 4 3\nf 5 7 8 6\nusemtl b\nf 1 5 6 2\nf 3 4 8 7\n"
             b"s 1\nf 1 3 7 5\nf -7 -3 -1 -5\n")
    put("obj_mesh", "cube-planar.obj", b"\x02" + bytes(cube))
    strip = (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
             b"f 1/1 2/2 3/3\nf 2/2 4/4 3/3\nf 1/1 5/1 2/2\n")
    put("obj_mesh", "degenerate-seam.obj", b"\x01" + strip)
    with open(os.path.join(ROOT, "examples", "scenes", "wall.obj"), "rb") as f:
        put("obj_mesh", "wall.obj", b"\x00" + f.read())


def capture_seeds():
    dirs = "[[0.0, 0.0], [45.0, 0.0], [45.0, 90.0], [45.0, 180.0], [45.0, 270.0]]"
    base = f"""version = 1
sampling = "rings:0x1,45x4"
directions_deg = {dirs}
naming = "tvTTT_pvPPP/tlTTT_plPPP_tvTTT_pvPPP.png"

[[rings]]
theta_deg = 0.0
count = 1
phi_offset_deg = 0.0

[[rings]]
theta_deg = 45.0
count = 4
phi_offset_deg = 0.0

[camera]
width = 64
height = 48
focal_px = 90.0
principal_point_px = [32.0, 24.0]
distance_mm = 500.0
bits = 12
frontal_axes = "x right, y up"
light = "point, 1 m"

[plate]
size_mm = 140.0
sample_mm = 80.0
point_markers_mm = [[60.0, 60.0], [-60.0, 60.0], [-60.0, -60.0], [60.0, -60.0], [0.0, 61.0]]
marker_radius_mm = 3.0
border_offset_mm = 50.0
border_width_mm = 4.0
"""
    full = base + """
[radiometry]
reference_white_dn = 3000.0
vignetting_cos_power = 4.0

[material]
kind = "woven"
size = 64
seed = 7
albedo = [0.5, 0.4, 0.3]
"""
    put("capture_toml", "rings.toml", base.encode())
    put("capture_toml", "full.toml", full.encode())
    ubo = ",\n  ".join("[%.1f, %.1f]" % d for d in ubo81_directions())
    named = base.replace('sampling = "rings:0x1,45x4"', 'sampling = "ubo81"')
    named = named.replace("directions_deg = " + dirs, "directions_deg = [\n  " + ubo + "]")
    named = re.sub(r"\[\[rings\]\][^\[]*", "", named)
    put("capture_toml", "ubo81.toml", named.encode())


def ubo81_directions():
    out = []
    for theta, n in zip([0, 15, 30, 45, 60, 75], [1, 6, 12, 18, 20, 24]):
        for k in range(n):
            out.append((float(theta), 0.0 if theta == 0 else k * 360.0 / n))
    return out


def zarr_seeds():
    for dtype, shape, chunk in [
        ("float32", [2, 3], [2, 3]),
        ("float16", [4, 4], [2, 2]),
        ("uint8", [3, 5], [3, 5]),
        ("float64", [1, 1, 2, 2, 3], [1, 1, 2, 2, 3]),
    ]:
        names = ["d%d" % i for i in range(len(shape))]
        put("zarr_array", "%s-%s.bin" % (dtype, "x".join(map(str, shape))),
            array_json(shape, chunk, dtype, names) + SEP + chunk_bytes(chunk, dtype))
    group = group_json({"note": "a group"})
    put("zarr_array", "group.bin", group)
    # The blosc chain (zstd, shuffle): a memcpyed frame, and a compressed one c-blosc wrote
    # (btf-core/tests/data/blosc, made by numcodecs).
    for name, shape, frame in [
        ("blosc-memcpyed-f16-3x5.bin", [3, 5], blosc_memcpyed(chunk_bytes([3, 5], "float16")[:-4], 2)),
        ("blosc-zstd-f16-1501.bin", [1501], blosc_fixture("f16_shuffle.blosc")),
    ]:
        j = json.loads(array_json(shape, shape, "float16", ["d%d" % i for i in range(len(shape))]))
        j["codecs"].insert(1, {"name": "blosc", "configuration": {
            "cname": "zstd", "clevel": 1, "shuffle": "shuffle", "typesize": 2, "blocksize": 0}})
        put("zarr_array", name, json.dumps(j, separators=(",", ":")).encode() + SEP
            + frame + struct.pack("<I", crc32c(frame)))


BLOSC_FIXTURES = os.path.join(ROOT, "btf-core", "tests", "data", "blosc")


def blosc_fixture(name):
    with open(os.path.join(BLOSC_FIXTURES, name), "rb") as f:
        return f.read()


def blosc_memcpyed(raw, typesize):
    """A blosc1 frame storing `raw` as it is (flags: shuffle, memcpyed, don't split, zstd)."""
    return struct.pack("<BBBBIII", 2, 1, 0x01 | 0x02 | 0x10 | 4 << 5, typesize, len(raw),
                       len(raw), len(raw) + 16) + raw


def blosc_seeds():
    # blosc_frame target: one frame, as c-blosc 1.21 wrote it (numcodecs) or by hand.
    for name in ["f16_shuffle", "f16_noshuffle", "f64_noshuffle_odd", "u8_shuffle",
                 "small_memcpyed"]:
        put("blosc_frame", name + ".bin", blosc_fixture(name + ".blosc"))
    put("blosc_frame", "memcpyed-u32.bin", blosc_memcpyed(bytes(range(200)), 4))


def btf_store_seeds():
    one = [ring(0.0, 1)]
    two = [ring(0.0, 1), ring(45.0, 2, 10.0)]
    for name, views, lights, w, h, dtype in [
        ("f32-1x1-2x2.bin", one, one, 2, 2, "float32"),
        ("f16-3x3-4x2.bin", two, two, 4, 2, "float16"),
    ]:
        attrs = {"btf": btf_meta("btf", views, lights, w, h), "complete": True}
        nv, nl = count(views), count(lights)
        arr = array_json([nv, nl, h, w, 3], [1, 1, h, w, 3], dtype,
                         ["view", "light", "y", "x", "channel"])
        put("btf_store", name,
            group_json(attrs) + SEP + arr + SEP + chunk_bytes([1, 1, h, w, 3], dtype))


def eigen_store_seeds():
    views = [ring(0.0, 1), ring(30.0, 3)]
    lights = [ring(0.0, 1), ring(45.0, 2)]
    for name, q, c, w, h in [("f16-c1.bin", "f16", 1, 2, 2), ("u8-c2.bin", "u8", 2, 3, 1)]:
        btf = btf_meta("eigen", views, lights, w, h)
        attrs = {"btf": btf, "eigen": {"components": c, "quantization": q}, "complete": True}
        v, l = count(views), count(lights)
        arrays = [
            array_json([v, h, w, 3], [1, h, w, 3], "float32", ["view", "y", "x", "channel"]),
            array_json([v, c, h, w, 3], [1, c, h, w, 3], "float16" if q == "f16" else "uint8",
                       ["view", "component", "y", "x", "channel"]),
            array_json([v, c, 2], [1, c, 2], "float32", ["view", "component", "scale_offset"]),
            array_json([v, l, c], [1, l, c], "float32", ["view", "light", "component"]),
            array_json([v, l], [1, l], "float64", ["view", "index"]),
        ]
        put("eigen_store", name, SEP.join([group_json(attrs)] + arrays))


def pvf_seeds():
    # pvf target: the first byte picks `!PVF06FC` (even) or `!PVF06FCR` (odd).
    put("pvf", "current-f32.bin", b"\x00" + pvf_after_signature(False))
    put("pvf", "current-rot-f16-p2.bin", b"\x01" + pvf_after_signature(True, size=2, p=2))
    put("pvf", "legacy-f32.bin", b"\x00" + pvf_after_signature(False, legacy=True))
    put("pvf", "light-rows-f64.bin", b"\x00" + pvf_after_signature(False, size=8, light_rows=True))


def ubo2014_seeds():
    # ubo2014 target: the first byte picks one of
    # 0 !FMF06FC, 1 !FMF06FCR, 2 !FMF12FCER, 3 !DFMF08FCR, 4 !PVF06FC, 5 !PVF06FCR,
    # 6 !BDIF06R2!, 7 none (the signature is in the data).
    w = h = 2
    texels, dirs, nc = w * h, len(VIEWS) * len(LIGHTS), 3
    fmf = common_header(False, w, h) + u32(1) + svd(nc * dirs, texels)
    put("ubo2014", "fmf06fc.bin", b"\x00" + fmf)
    fmf_r = common_header(True, 3, 1) + u32(1) + svd(nc * 3, dirs, p=2, size=2)  # 3x1 texels
    put("ubo2014", "fmf06fcr-texel-rows.bin", b"\x01" + fmf_r)
    hm = u32(1) + u32(2) + scalars([0.0, 0.5], 2)
    fmf12 = common_header(True, w, h) + bytes([2]) + u32(1) + hm + u32(1) + svd(nc * dirs, texels)
    put("ubo2014", "fmf12fcer-heightmap.bin", b"\x02" + fmf12)
    dfmf = common_header(True, w, h) + u32(1) + struct.pack("<i", 3) + f32s(0.1, 0.2, 0.3)
    dfmf += f32s(1, 0, 0, 0, 1, 0, 0, 0, 1)
    for _ in range(nc):
        dfmf += svd(dirs, texels)
    put("ubo2014", "dfmf-pca.bin", b"\x03" + dfmf)
    put("ubo2014", "pvf.bin", b"\x04" + pvf_after_signature(False))
    put("ubo2014", "pvf-rot.bin", b"\x05" + pvf_after_signature(True))
    # BDI, full (compression 0): mask, rotations, chunks of `scan_lines` rows of ABRDFs.
    lines = 1
    abrdf = nc * len(VIEWS) * len(LIGHTS)
    bdi = meta_block(4) + sampling() + u32(w) + u32(h) + u32(lines) + bytes([0])
    bdi += bytes([1] * (w * h)) + rotations(1)
    for c in range(h // lines):
        n = w * lines
        bdi += u32(n * abrdf * 2) + scalars([0.01 * (i % 50) for i in range(n * abrdf)], 2)
    put("ubo2014", "bdi-full.bin", b"\x06" + bdi)
    # BDI, sparse (compression 2): only the texels whose mask byte is set are stored.
    mask = bytes([1, 0, 0, 1])
    sparse = meta_block(4) + sampling() + u32(w) + u32(h) + u32(lines) + bytes([2]) + mask
    sparse += rotations(0)
    stored = sum(1 for b in mask if b)
    left = stored
    while left:
        n = min(left, w * lines)
        sparse += u32(n * abrdf * 2) + scalars([0.25] * (n * abrdf), 2)
        left -= n
    put("ubo2014", "bdi-sparse.bin", b"\x06" + sparse)
    # The signature in the data itself (selector 7), an old metadata version.
    legacy_meta = b"!FMF06FC" + common_header(False, w, h, version=1) + u32(1) + svd(nc * dirs, texels)
    put("ubo2014", "raw-fmf-meta-v1.bin", b"\x07" + legacy_meta)


def bcc(curves, up=2, info=b"seed"):
    """BCC (yarn::io::bcc): 64-byte header, then per curve an i32 count (negative: closed)
    and little-endian f32 xyz."""
    total = sum(len(pts) for pts, _ in curves)
    head = b"BCC" + bytes([0x44]) + b"C0" + bytes([3, up])
    head += struct.pack("<QQ", len(curves), total) + info.ljust(40, b"\0")[:40]
    body = b""
    for pts, closed in curves:
        body += struct.pack("<i", -len(pts) if closed else len(pts))
        for p in pts:
            body += struct.pack("<3f", *p)
    return head + body


def bcc_seeds():
    line = [(0.001 * i, 0.0002 * (i % 3), 0.0) for i in range(6)]
    ring = [(0.0, 0.0, 0.0), (0.002, 0.0, 0.001), (0.001, 0.002, 0.0)]
    put("bcc", "open-and-closed.bcc", bcc([(line, False), (ring, True)]))
    put("bcc", "y-up.bcc", bcc([(ring, True)], up=1))
    put("bcc", "two-points.bcc", bcc([(line[:2], False)]))


def main():
    if os.path.isdir(OUT):
        shutil.rmtree(OUT)
    env_seeds()
    raw_image_seeds()
    ubo2003_image_seeds()
    scene_seeds()
    obj_seeds()
    capture_seeds()
    zarr_seeds()
    btf_store_seeds()
    eigen_store_seeds()
    pvf_seeds()
    ubo2014_seeds()
    bcc_seeds()
    blosc_seeds()
    total = 0
    for t in sorted(os.listdir(OUT)):
        files = os.listdir(os.path.join(OUT, t))
        size = sum(os.path.getsize(os.path.join(OUT, t, f)) for f in files)
        total += size
        print("%-14s %2d seeds %6d bytes" % (t, len(files), size))
    print("%-14s          %6d bytes" % ("total", total))


if __name__ == "__main__":
    sys.exit(main())
