//! The knit commands under the same rules as every other writer (issue #26 holds for
//! commands added later): `btf knit chart|mesh|skeleton|fibers|ref` and `btf synth
//! material --kind yarn` refuse an output that is one of their inputs (chart, yarn TOML,
//! BCC curves) and leave it untouched; a BCC file whose header claims more than the file
//! holds, that is truncated, or that holds a NaN is refused with the file and curve named,
//! without an abort, and leaves no output or temporary behind.

use crate::common::Dir;
use crate::hostile::{assert_no_panic, leftovers, snapshot};

/// A folder with a one-row chart, a yarn TOML (the `fine-2ply` preset written out) and
/// the chart's yarn centre lines as BCC.
fn knit_fixture() -> Dir {
    let d = Dir::new();
    std::fs::write(d.path("c.chart"), "name: c\nkp\n").unwrap();
    d.ok(&["knit", "skeleton", "--chart", "c.chart", "--yarn", "fine-2ply", "-o", "y.bcc"]);
    let yarn = yarn::params::YarnParams::preset("fine-2ply").unwrap().to_toml().unwrap();
    std::fs::write(d.path("y.toml"), yarn).unwrap();
    d
}

#[test]
fn knit_writers_refuse_their_inputs_as_outputs() {
    let d = knit_fixture();
    let inputs = ["c.chart", "y.toml", "y.bcc"].map(|n| (n, snapshot(&d.path(n))));
    let cases: &[&[&str]] = &[
        &["knit", "chart", "c.chart", "-o", "c.chart"],
        &["knit", "mesh", "--chart", "c.chart", "-o", "c.chart"],
        &["knit", "skeleton", "--chart", "c.chart", "-o", "./c.chart"],
        &["knit", "skeleton", "--chart", "c.chart", "--yarn", "y.toml", "-o", "y.toml"],
        &["knit", "fibers", "--chart", "c.chart", "--yarn", "y.toml", "-o", "x/../y.toml"],
        &["knit", "ref", "--bcc", "y.bcc", "--yarn", "y.toml", "--light", "dir:0,0", "-o", "y.bcc"],
        &["knit", "ref", "--chart", "c.chart", "--light", "dir:0,0", "-o", "c.chart"],
        &[
            "synth", "material", "--kind", "yarn", "--chart", "c.chart", "--size", "4", "-o",
            "c.chart",
        ],
        &["synth", "material", "--kind", "yarn", "--yarn", "y.toml", "--size", "4", "-o", "y.toml"],
    ];
    for args in cases {
        let err = d.fails(args);
        assert_no_panic(&err);
        assert!(err.contains("refusing to write"), "btf {args:?}: {err}");
        for (name, before) in &inputs {
            assert_eq!(&snapshot(&d.path(name)), before, "btf {args:?} changed {name}");
        }
    }
    assert!(leftovers(&d.path("")).is_empty(), "{:?}", leftovers(&d.path("")));
}

#[test]
fn bad_bcc_files_are_refused_by_name_and_leave_nothing() {
    let d = knit_fixture();
    let good = std::fs::read(d.path("y.bcc")).unwrap();
    assert!(good.len() > 64 + 4 + 12, "the fixture's BCC holds curves");
    let u64_at = |b: &[u8], o: usize| u64::from_le_bytes(b[o..o + 8].try_into().unwrap());
    let (curves, points) = (u64_at(&good, 8), u64_at(&good, 16));
    assert!(curves >= 1 && points >= curves);

    // A header claiming 2^40 control points in a file of a few kB: refused before any
    // allocation of that size.
    let mut huge = good.clone();
    huge[16..24].copy_from_slice(&(1u64 << 40).to_le_bytes());
    std::fs::write(d.path("huge.bcc"), &huge).unwrap();
    // Cut in the middle of the first curve's points.
    std::fs::write(d.path("cut.bcc"), &good[..64 + 4 + 6]).unwrap();
    // A NaN in curve 0, point 1 (the x coordinate): header 64 bytes, count 4, 12 per point.
    let mut nan = good.clone();
    nan[64 + 4 + 12..64 + 4 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(d.path("nan.bcc"), &nan).unwrap();

    for (file, named) in [
        ("huge.bcc", "control points"),
        ("cut.bcc", "truncated"),
        ("nan.bcc", "curve 0, control point 1"),
    ] {
        let err = d.fails(&["knit", "ref", "--bcc", file, "--light", "dir:0,0", "-o", "out.exr"]);
        assert_no_panic(&err);
        assert!(err.contains(file), "{file}: the message names the file: {err}");
        assert!(err.contains(named), "{file}: the message names '{named}': {err}");
        assert!(!d.path("out.exr").exists(), "{file}: an output was written");
    }
    assert!(leftovers(&d.path("")).is_empty(), "{:?}", leftovers(&d.path("")));
}
