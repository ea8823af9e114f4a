//! End-to-end tests of `btf synth garment` (issue #22): the command is deterministic,
//! writes one manifold OBJ whose boundary loops are the garment's openings, and refuses bad
//! parameters naming the parameter; interrupted, it resumes to the same file. Coarse meshes (`--vertices 1500`) keep each run to
//! seconds; full sizes are in BENCHMARKS.md.

use crate::common::Dir;

/// Positions and faces of an OBJ written by the binary.
fn read_obj(path: &std::path::Path) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut v = Vec::new();
    let mut f = Vec::new();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f64> = w.map(|x| x.parse().unwrap()).collect();
                v.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let c: Vec<usize> =
                    w.map(|x| x.split('/').next().unwrap().parse::<usize>().unwrap() - 1).collect();
                f.push([c[0], c[1], c[2]]);
            }
            _ => {}
        }
    }
    (v, f)
}

/// Number of boundary loops (edges used once, chained) and of edges used more than twice.
fn boundary(faces: &[[usize; 3]]) -> (usize, usize) {
    use std::collections::HashMap;
    let mut count: HashMap<(usize, usize), usize> = HashMap::new();
    for t in faces {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let non_manifold = count.values().filter(|&&c| c > 2).count();
    let mut adj: HashMap<usize, Vec<usize>> = HashMap::new();
    for (&(a, b), &c) in &count {
        if c == 1 {
            adj.entry(a).or_default().push(b);
            adj.entry(b).or_default().push(a);
        }
    }
    // Loops = connected components of the boundary graph (every vertex has degree 2).
    let mut seen = std::collections::HashSet::new();
    let mut loops = 0;
    let mut keys: Vec<usize> = adj.keys().copied().collect();
    keys.sort_unstable();
    for s in keys {
        if !seen.insert(s) {
            continue;
        }
        loops += 1;
        let mut stack = vec![s];
        while let Some(a) = stack.pop() {
            for &b in &adj[&a] {
                if seen.insert(b) {
                    stack.push(b);
                }
            }
        }
    }
    (loops, non_manifold)
}

#[test]
fn garment_tshirt_is_deterministic_and_has_four_openings() {
    let d = Dir::new();
    let args = ["synth", "garment", "--kind", "tshirt", "--size", "M", "--vertices", "1500"];
    let mut a = args.to_vec();
    a.extend(["-o", "a.obj"]);
    d.ok(&a);
    let mut b = args.to_vec();
    b.extend(["--out", "b.obj"]);
    d.ok(&b);
    let (ta, tb) =
        (std::fs::read(d.path("a.obj")).unwrap(), std::fs::read(d.path("b.obj")).unwrap());
    assert!(ta == tb, "two runs wrote different files");
    // Interrupted (after its third snapshot, as a kill would leave it) and resumed, a run
    // writes the same file; the snapshot is gone once the garment is written.
    let mut c = args.to_vec();
    c.extend(["-o", "c.obj", "--snapshot-every", "0"]);
    let mut stopped = c.clone();
    stopped.extend(["--stop-after-snapshots", "3"]);
    let e = d.fails(&stopped);
    assert!(e.contains("--resume") && d.path("c.obj.partial").is_file(), "{e}");
    assert!(!d.path("c.obj").exists(), "an interrupted run wrote its output");
    // Other parameters do not resume it.
    let mut other = stopped.clone();
    other.extend(["--length", "0.7", "--resume"]);
    let e = d.fails(&other);
    assert!(e.contains("other parameters"), "{e}");
    c.push("--resume");
    let o = d.btf(&c);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("resuming from"), "{err}");
    assert!(std::fs::read(d.path("c.obj")).unwrap() == ta, "the resumed run wrote another file");
    assert!(!d.path("c.obj.partial").exists(), "the snapshot was left behind");
    let (v, f) = read_obj(&d.path("a.obj"));
    // The mesher aims at the vertex count; seams welded remove the partners' duplicates.
    assert!((1000..=1800).contains(&v.len()), "{} vertices", v.len());
    assert_eq!(boundary(&f), (4, 0), "neck, hem and two cuffs; no non-manifold edge");
}

/// The crossing pairs `btf synth garment` reports on its summary line.
fn crossings(stderr: &str) -> usize {
    let before = stderr.split(" crossing triangle pairs").next().unwrap();
    before.rsplit(' ').next().unwrap().parse().unwrap()
}

/// Cloth–cloth contact (on unless `--no-cloth-contact`) makes the trousers free of
/// crossings (their legs cross at the crotch without it), at rest, with their three
/// openings.
#[test]
fn garment_cloth_contact_keeps_the_trousers_legs_apart() {
    let d = Dir::new();
    let base = ["synth", "garment", "--kind", "trousers", "--vertices", "1500"];
    let run = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        let o = d.btf(&a);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{err}");
        err
    };
    let plain = run(&["--no-cloth-contact", "-o", "plain.obj"]);
    let contact = run(&["-o", "contact.obj"]);
    assert!(crossings(&plain) > 0, "{plain}");
    assert_eq!(crossings(&contact), 0, "{contact}");
    assert!(contact.contains("rest reached"), "{contact}");
    let (_, f) = read_obj(&d.path("contact.obj"));
    assert_eq!(boundary(&f), (3, 0), "waist and two hems; no non-manifold edge");
}

#[test]
fn garment_body_is_closed() {
    let d = Dir::new();
    d.ok(&["synth", "garment", "--kind", "body", "--size", "S", "-o", "body.obj"]);
    let (v, f) = read_obj(&d.path("body.obj"));
    assert_eq!(boundary(&f), (0, 0), "a closed manifold mesh");
    // Size S is 1.68 m tall: the mesh spans that height to within the 12 mm grid step.
    let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p[2]), hi.max(p[2])));
    assert!((hi - lo - 1.68).abs() < 0.03, "height {}", hi - lo);
}

#[test]
fn garment_refuses_bad_parameters_naming_them() {
    let d = Dir::new();
    let base = ["synth", "garment", "--kind", "tshirt", "--vertices", "1500", "-o", "g.obj"];
    let with = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        let e = d.fails(&a);
        eprintln!("{extra:?}: {e}");
        e
    };
    assert!(with(&["--height=-1.7"]).contains("--height"));
    assert!(with(&["--chest", "0"]).contains("--chest"));
    assert!(with(&["--sleeve-length", "2.5"]).contains("--sleeve-length"));
    assert!(with(&["--sleeve-length=-0.2"]).contains("--sleeve-length"));
    assert!(with(&["--length", "3"]).contains("--length"));
    assert!(with(&["--size", "XL"]).contains("--size"));
    assert!(
        d.fails(&["synth", "garment", "--kind", "skirt", "--vertices", "10", "-o", "g.obj"])
            .contains("--vertices")
    );
    assert!(d.fails(&["synth", "garment", "--kind", "dress", "-o", "g.obj"]).contains("--kind"));
    // A mesh finer than the cloth's half-thickness (the scarf's small panel at 40 000).
    let e = d.fails(&["synth", "garment", "--kind", "scarf", "--vertices", "40000", "-o", "g.obj"]);
    assert!(e.contains("--vertices") && e.contains("half-thickness"), "{e}");
    assert!(
        d.fails(&["synth", "garment", "--kind", "skirt", "--sleeve-length", "0.3", "-o", "g.obj"])
            .contains("--sleeve-length")
    );
    // A body that is not closed: one triangle.
    std::fs::write(d.path("open.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert!(with(&["--body", "open.obj"]).contains("--body"));
    assert!(!d.path("g.obj").exists(), "nothing written when refused");
}
