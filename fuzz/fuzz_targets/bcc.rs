//! Fuzzes BCC yarn-curve files (`yarn::io::bcc`, behind `btf knit` and every reader of
//! Yuksel's models): the bytes are parsed in memory and, through a file on a tmpfs, by
//! `read_bcc` (which checks the header against the file size before reading the body).
//! Whatever parses must write back to bytes that parse to the same curves.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarn::io::bcc::{bcc_bytes, parse_bcc, read_bcc};

fuzz_target!(|data: &[u8]| {
    let parsed = parse_bcc(data, "fuzz.bcc");
    let path = btf_fuzz::put("in.bcc", data);
    let read = read_bcc(&path);
    assert_eq!(parsed.is_ok(), read.is_ok());
    if let Ok(f) = parsed {
        let bytes = bcc_bytes(&f.set, &f.info).expect("a parsed set writes");
        let again = parse_bcc(&bytes, "again.bcc").expect("written bytes parse");
        assert_eq!(again.set.curves.len(), f.set.curves.len());
        for (a, b) in again.set.curves.iter().zip(&f.set.curves) {
            assert_eq!(a.points, b.points);
            assert_eq!(a.closed, b.closed);
        }
    }
});
