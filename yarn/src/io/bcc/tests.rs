//! BCC checks: bit-exact round trip, refusals of hostile headers and curves (named), y-up.

use super::*;

fn sample_set() -> YarnSet {
    let open: Vec<V3> =
        (0..7).map(|i| [0.001 * i as f64, 0.0003 * (i as f64).sin(), 0.0]).collect();
    let ring = vec![[0.0, 0.0, 0.0], [0.002, 0.0, 0.001], [0.001, 0.002, 0.0]];
    let course = vec![[0.0, 0.0, 0.0], [0.003, 0.001, 0.0005], [0.006, -0.001, 0.0]];
    YarnSet::new(
        vec![
            YarnCurve::open(open).unwrap(),
            YarnCurve::closed(ring).unwrap(),
            YarnCurve::periodic(course, [0.009, 0.0, 0.0]).unwrap(),
        ],
        None,
    )
    .unwrap()
}

fn patch(bytes: &mut [u8], at: usize, v: &[u8]) {
    bytes[at..at + v.len()].copy_from_slice(v);
}

#[test]
fn round_trip_is_bit_exact() {
    let set = sample_set();
    let bytes = bcc_bytes(&set, "yarn test").unwrap();
    let back = parse_bcc(&bytes, "mem").unwrap();
    assert_eq!(back.info, "yarn test");
    assert_eq!(back.up_dimension, 2);
    assert_eq!(back.set.curves.len(), 3);
    assert!(back.set.curves[1].closed && !back.set.curves[2].closed);
    assert_eq!(back.set.curves[2].points.len(), 3 + 3);
    let again = bcc_bytes(&back.set, "yarn test").unwrap();
    assert_eq!(bytes, again);
    for (a, b) in set.curves[0].points.iter().zip(&back.set.curves[0].points) {
        assert_eq!(a.map(|v| v as f32 as f64), *b);
    }
    // The periodic course's period is reproduced by the open curve's inner segments.
    let (c, o) = (&set.curves[2], &back.set.curves[2]);
    for k in 0..=30 {
        let u = 3.0 * k as f64 / 30.0;
        assert!(vec3::distance(c.point(u), o.point(u + 1.0)) < 1e-9);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("set.bcc");
    write_bcc(&path, &set, "yarn test").unwrap();
    assert_eq!(read_bcc(&path).unwrap(), back);
}

#[test]
fn hostile_files_are_refused_naming_the_curve() {
    let good = bcc_bytes(&sample_set(), "").unwrap();
    // Truncated.
    let e = parse_bcc(&good[..good.len() - 5], "t.bcc").unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");
    // Counts larger than the file allows: refused from the header, nothing allocated.
    let mut big = good.clone();
    patch(&mut big, 8, &(1u64 << 40).to_le_bytes());
    let e = parse_bcc(&big, "big.bcc").unwrap_err().to_string();
    assert!(e.contains("header claims 1099511627776 curves"), "{e}");
    let mut huge = good.clone();
    patch(&mut huge, 16, &u64::MAX.to_le_bytes());
    assert!(matches!(parse_bcc(&huge, "h.bcc"), Err(Error::Limit(_))));
    // A curve count larger than the points left (curve 0 claims 10⁶).
    let mut over = good.clone();
    patch(&mut over, 64, &1_000_000i32.to_le_bytes());
    let e = parse_bcc(&over, "o.bcc").unwrap_err().to_string();
    assert!(e.contains("curve 0") && e.contains("remain"), "{e}");
    // Negative counts: curve 1 is a closed loop; make it a closed 2-point curve.
    let second = 64 + 4 + 12 * 7;
    let mut neg = good.clone();
    patch(&mut neg, second, &(-2i32).to_le_bytes());
    let e = parse_bcc(&neg, "n.bcc").unwrap_err().to_string();
    assert!(e.contains("curve 1"), "{e}");
    let mut min = good.clone();
    patch(&mut min, second, &i32::MIN.to_le_bytes());
    let e = parse_bcc(&min, "m.bcc").unwrap_err().to_string();
    assert!(e.contains("curve 1"), "{e}");
    // NaN in curve 1, point 2.
    let mut nan = good.clone();
    patch(&mut nan, second + 4 + 24 + 4, &f32::NAN.to_le_bytes());
    let e = parse_bcc(&nan, "nan.bcc").unwrap_err().to_string();
    assert!(e.contains("curve 1, control point 2"), "{e}");
    // Other types, byte counts, dimensions: unsupported.
    for (at, v) in [(4usize, b'B'), (5, b'1'), (3, 0x48), (6, 2), (7, 9)] {
        let mut u = good.clone();
        u[at] = v;
        assert!(matches!(parse_bcc(&u, "u.bcc"), Err(Error::Unsupported(_))), "byte {at}");
    }
    assert!(parse_bcc(b"BCC", "short").is_err());
}

#[test]
fn y_up_files_are_turned_z_up() {
    let set =
        YarnSet::new(vec![YarnCurve::open(vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]).unwrap()], None)
            .unwrap();
    let mut bytes = bcc_bytes(&set, "").unwrap();
    bytes[7] = 1;
    let f = parse_bcc(&bytes, "y.bcc").unwrap();
    assert_eq!(f.set.curves[0].points[1], [1.0, -3.0, 2.0]);
}
