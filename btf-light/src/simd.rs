//! Which vector code the ray lanes of the visibility rasteriser (`visibility::ray_lanes`)
//! and the gather's source codes (`gather::fast`) run: the path the whole toolkit runs,
//! [`btf_core::simd::Isa`], chosen by `BTF_SIMD` (`scalar`, `avx2`, `avx512`, `neon`,
//! `auto`) or, by default, the best the CPU has.
//!
//! | [`Isa`] | packet traversal | frame rays, near-triangle octets, source codes |
//! |---|---|---|
//! | `avx512` | 16 lanes, `#[target_feature(enable = "avx512f")]` | 8 lanes, AVX2 |
//! | `avx2` | 8 lanes, AVX2 | 8 lanes, AVX2 |
//! | `neon`, `scalar` | 8 lanes, baseline target (SSE2 on x86-64, NEON on aarch64) | the same |
//!
//! Every path computes the same bits: a lane performs the scalar test's `f32` operations in
//! the scalar test's order (no fused multiply-add — Rust never contracts `a * b + c`, and
//! none of these kernels calls `mul_add` — IEEE division, the same `min`/`max` NaN rules),
//! so the choice changes the speed only. The `avx2` path of `btf-core` also asks for FMA
//! and F16C (its kernels fuse); these kernels need only AVX2, but follow the same switch so
//! that one variable forces one path everywhere (an AVX2 CPU without FMA — none shipped
//! since 2013 — gets the portable code).

pub use btf_core::simd::Isa;

/// The vector code of this crate for a path. Constructed only by [`Lanes::of`], which
/// checks that the CPU runs it: the x86 variants are what makes the `target_feature`
/// calls sound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Lanes {
    /// Baseline target (and NEON on aarch64, where it is part of the baseline).
    Portable,
    /// x86-64 AVX2: 8 `f32` lanes.
    #[cfg(target_arch = "x86_64")]
    Avx2,
    /// x86-64 AVX-512F: 16 lanes for the packet traversal, AVX2 elsewhere.
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Lanes {
    /// The code for `isa`. Panics if this CPU cannot run `isa` (`Isa::choose` refuses such a
    /// `BTF_SIMD` before any kernel runs). `neon` is the portable code, which gives the
    /// same bits on any CPU, so it is accepted everywhere (tests run it on x86-64 too).
    pub(crate) fn of(isa: Isa) -> Lanes {
        assert!(isa.supported() || isa == Isa::Neon, "the {isa} kernels cannot run on this CPU");
        match isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => Lanes::Avx512,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => Lanes::Avx2,
            _ => Lanes::Portable,
        }
    }

    /// The code for the path `BTF_SIMD` asks for ([`Isa::active`], read once per process).
    pub(crate) fn active() -> Lanes {
        Lanes::of(Isa::active())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_supported_path_maps_to_its_own_code() {
        for isa in Isa::supported_all() {
            let name = match Lanes::of(isa) {
                Lanes::Portable => ["scalar", "neon"].into_iter().find(|n| *n == isa.name()),
                #[cfg(target_arch = "x86_64")]
                Lanes::Avx2 => Some("avx2"),
                #[cfg(target_arch = "x86_64")]
                Lanes::Avx512 => Some("avx512"),
            };
            assert_eq!(name, Some(isa.name()), "{isa}");
        }
        assert_eq!(Lanes::of(Isa::Neon), Lanes::Portable);
        assert_eq!(Lanes::active(), Lanes::of(Isa::active()));
    }
}
