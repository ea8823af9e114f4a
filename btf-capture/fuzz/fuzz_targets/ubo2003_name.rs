//! Fuzzes the UBO2003 file-name angle parser: any name gives angles or an error.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(name) = std::str::from_utf8(data) {
        if let Ok(a) = btf_capture::bonn::ubo2003::parse_name(name) {
            assert!(a.theta_light.is_finite() && a.phi_view.is_finite());
        }
    }
});
