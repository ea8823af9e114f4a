//! Class 4: a refused import or export leaves nothing behind: no `NAME.partial`, no
//! temporary file, no half-written output.

use crate::hostile::{assert_no_panic, fixture, leftovers};

#[test]
fn refused_imports_leave_nothing() {
    let d = fixture();
    d.ok(&["export", "A.btf", "--format", "ubo2003", "--image", "png", "-o", "ex"]);
    // One image truncated: the import reads some images, then refuses.
    let sub =
        std::fs::read_dir(d.path("ex")).unwrap().flatten().find(|e| e.path().is_dir()).unwrap();
    let img = std::fs::read_dir(sub.path()).unwrap().flatten().last().unwrap().path();
    let bytes = std::fs::read(&img).unwrap();
    std::fs::write(&img, &bytes[..bytes.len() / 2]).unwrap();
    let err = d.fails(&["import", "ubo2003", "ex", "-o", "I.btf"]);
    assert_no_panic(&err);
    assert!(!d.path("I.btf").exists());
    assert_eq!(leftovers(d.tmp.path()), Vec::<String>::new(), "{err}");

    d.ok(&["export", "B.eig", "--format", "pvf", "-o", "b.pvf"]);
    let pvf = std::fs::read(d.path("b.pvf")).unwrap();
    std::fs::write(d.path("t.pvf"), &pvf[..pvf.len() - 100]).unwrap();
    let err = d.fails(&["import", "ubo2014", "t.pvf", "--eigen", "-o", "T.eig"]);
    assert_no_panic(&err);
    assert!(!d.path("T.eig").exists());
    assert_eq!(leftovers(d.tmp.path()), Vec::<String>::new(), "{err}");
}

#[test]
fn refused_exports_leave_nothing() {
    let d = fixture();
    std::fs::create_dir(d.path("folder.npy")).unwrap();
    let err = d.fails(&["export", "A.btf", "--format", "npy", "--slot", "0", "-o", "folder.npy"]);
    assert!(err.contains("folder"), "{err}");
    let err = d.fails(&["export", "A.btf", "--format", "npy", "--slot", "99", "-o", "x.npy"]);
    assert!(err.contains("--slot 99"), "{err}");
    assert!(!d.path("x.npy").exists());
    assert_eq!(leftovers(d.tmp.path()), Vec::<String>::new());
}
