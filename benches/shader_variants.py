#!/usr/bin/env python3
"""Writes the timing-only variants of the BTF pass's WGSL behind BENCHMARKS.md #5 ("Where the
remaining overhead sits"): each removes one part of the per-pixel work so that the cost sweep
can time what is left. The images they render are not valid; only their frame times count.

Usage: python3 benches/shader_variants.py OUT_DIR
Then, per variant (idle machine; `benches/quiet.sh` pauses everything else):
  BTF_PASS_WGSL=OUT_DIR/NAME.wgsl BTF_SWEEP_SIZE=128 BTF_SWEEP_COMPONENTS=4 \
    cargo bench -p btf-render --bench sweep
and read the row "| 4 | per-pixel | four |".
"""
import os
import sys

SRC = os.path.join(os.path.dirname(__file__), "..", "btf-render", "src")


def replace(text, old, new):
    """`text` with `old` replaced once; fails when the shader changed under the script."""
    if old not in text:
        sys.exit(f"shader_variants.py: pattern not found (the shader changed):\n{old}")
    return text.replace(old, new, 1)


GAMMA_ROW = """fn gamma_row(e: u32, g: u32) -> vec4<f32> {
    if (PACKED) {"""
BIAS_OF = """fn bias_of(e: u32) -> f32 {
    let g = group_count();"""
# The weight rows replaced by constants; the operands stay alive so the compiler cannot drop
# the index arithmetic.
GAMMA_CONST = """fn gamma_row(e: u32, g: u32) -> vec4<f32> {
    if (e < 0xffffffffu) { return vec4<f32>(f32(e + g) * 1e-9); }
    if (PACKED) {"""
BIAS_CONST = """fn bias_of(e: u32) -> f32 {
    if (e < 0xffffffffu) { return f32(e) * 1e-9; }
    let g = group_count();"""


def no_weight_rows(text):
    return replace(replace(text, GAMMA_ROW, GAMMA_CONST), BIAS_OF, BIAS_CONST)


VIEW = """fn view_weights(a: vec2<f32>, four: bool) -> W4 {
    return interp_weights(VIEW, a, four);"""
VIEW_CONST = """fn view_weights(a: vec2<f32>, four: bool) -> W4 {
    return W4(vec4<u32>(0u, 1u, 2u, 3u), vec4<f32>(0.25) + vec4<f32>(a.x * 1e-9), select(1u, 4u, four));"""
LIGHT = """fn light_weights(a: vec2<f32>, four: bool) -> W4 {
    if (!(a.x < 90.0)) {"""
LIGHT_CONST = """fn light_weights(a: vec2<f32>, four: bool) -> W4 {
    if (a.x < 1000.0) { return W4(vec4<u32>(0u, 1u, 2u, 3u), vec4<f32>(0.25) + vec4<f32>(a.x * 1e-9), select(1u, 4u, four)); }
    if (!(a.x < 90.0)) {"""

READS_ONLY = """fn slot_pixel(j: u32, uv: vec2<f32>) -> vec3<f32> {
    let g_count = samplings.info.x;
    var acc = textureSampleGrad(mean_tex, tex_sampler, uv, j, duv_dx, duv_dy);
    for (var g = 0u; g < g_count; g = g + 1u) {
        let layer = j * 3u * g_count + 3u * g;
        acc = acc + textureSampleGrad(eigen_tex, tex_sampler, uv, layer, duv_dx, duv_dy);
        acc = acc + textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 1u, duv_dx, duv_dy);
        acc = acc + textureSampleGrad(eigen_tex, tex_sampler, uv, layer + 2u, duv_dx, duv_dy);
    }
    reads = reads + 1u + 3u * g_count;
    return acc.rgb * le[0];
}

"""

TRIVIAL_FS = (
    """fn fs_pixel(in: VertexOut) -> @location(0) vec4<f32> {
    let rgb = pixel_lights(in);""",
    """fn fs_pixel(in: VertexOut) -> @location(0) vec4<f32> {
    let rgb = vec3<f32>(in.uv, 0.0);""",
)


# The layered variants of session 6 (c = 4 only: one group, three eigentexture layers per
# slot): each keeps the BTF pipeline and the reconstruction's reads (counted, so the bound
# matches) and adds one part of the per-pixel work, so that successive differences are what
# each part costs.
FS_PIXEL = """fn fs_pixel(in: VertexOut) -> @location(0) vec4<f32> {
    let rgb = pixel_lights(in);
    count_reads();
    return vec4<f32>(rgb, 1.0);
}"""
LAYER_SETUP = """    let uv = tex_uv(in.uv);
    duv_dx = dpdx(uv);
    duv_dy = dpdy(uv);
"""
HASHED_SLOTS = (
    "    let nslots = 4u - select(0u, 1u, fract(in.clip.x * 0.37 + in.clip.y * 0.61) < 0.3);\n"
)
VIEWS = """    let v = to_camera(in.world);
    let f = tangent_frame(in, v);
    let views = view_weights(dir_angles(vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n))), VIEW_FOUR);
"""
LIGHTS = "    let lit = gather_lights(in, f);\n"
OUT = "    return vec4<f32>(acc.rgb * OUT_SCALE + vec3<f32>(acc.a * 1e-6), 1.0);"


def slot_reads(slot, weight, count):
    return f"""    var acc = vec4<f32>(0.0);
    reads = 0u;
    for (var m = 0u; m < {count}; m = m + 1u) {{
        let j = {slot};
        var s = textureSampleGrad(mean_tex, tex_sampler, uv, j, duv_dx, duv_dy);
        for (var r = 0u; r < 3u; r = r + 1u) {{
            s = s + textureSampleGrad(eigen_tex, tex_sampler, uv, j * 3u + r, duv_dx, duv_dy);
        }}
        acc = acc + {weight} * s;
        reads = reads + 4u;
    }}
    count_reads();
"""


def layered(text, body, scale="1.0"):
    return replace(text, FS_PIXEL, "fn fs_pixel(in: VertexOut) -> @location(0) vec4<f32> {\n"
                   + LAYER_SETUP + body + OUT.replace("OUT_SCALE", scale) + "\n}")


def layered_variants(src):
    lit_scale = "le[0] * dot(lw[0].w, vec4<f32>(1.0))"
    return {
        "layer_pipeline_reads": layered(src, HASHED_SLOTS + slot_reads("m", "1.0", "nslots")),
        "layer_view_weights": layered(src, VIEWS + HASHED_SLOTS + slot_reads("m", "views.w[m]", "nslots")),
        "layer_view_slots": layered(src, VIEWS + slot_reads("views.idx[m]", "views.w[m]", "views.n")),
        "layer_lights": layered(
            src,
            VIEWS.replace("    let views", LIGHTS + "    let views")
            + slot_reads("views.idx[m]", "views.w[m]", "views.n"),
            lit_scale,
        ),
    }


def reads_only(text):
    start = text.index("fn slot_pixel(j: u32, uv: vec2<f32>) -> vec3<f32> {")
    end = text.index("fn count_reads() {")
    return text[:start] + READS_ONLY + text[end:]


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    src = "".join(
        open(os.path.join(SRC, f), encoding="utf-8").read()
        for f in ("interp.wgsl", "btf_pass.wgsl", "btf_vertex.wgsl")
    )
    const = replace(replace(src, VIEW, VIEW_CONST), LIGHT, LIGHT_CONST)
    variants = {
        "as_is": src,
        "no_weight_rows": no_weight_rows(src),
        "constant_weights": const,
        "no_weight_rows_constant_weights": no_weight_rows(const),
        "reads_only": reads_only(src),
        "reads_only_constant_view": replace(reads_only(src), VIEW, VIEW_CONST),
        "trivial_fragment": replace(src, *TRIVIAL_FS),
        **layered_variants(src),
    }
    for name, text in variants.items():
        path = os.path.join(out, f"{name}.wgsl")
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        print(path)


if __name__ == "__main__":
    main()
