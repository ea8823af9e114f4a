//! Which instruction set the dense kernels of the per-slot PCA (`kernels`) use. (The ray
//! lanes and gathers of `btf-light` choose AVX2 or AVX-512 by run-time detection of their
//! own and do not read `BTF_SIMD`.)
//!
//! [`Isa::active`] is the best path the CPU supports — AVX-512, else AVX2 + FMA + F16C,
//! else NEON on aarch64, else the portable ("scalar") code — unless the environment
//! variable `BTF_SIMD` forces one: `scalar`, `avx2`, `avx512`, `neon` or `auto` (the
//! default). A forced path the CPU cannot run is an error ([`Isa::from_env`]), never a
//! silent fallback: entry points that return a `Result` (`compress`) report it; a kernel
//! reached without such a check panics with the same message. Tests and benchmarks force
//! each path through this switch, or hand an [`Isa`] to the kernels' `_with` variants.
//!
//! What the paths compute (see `btf-core/README.md`, "Dense kernels"): every SIMD path
//! (AVX-512, AVX2, NEON) performs the same fused multiply-adds in the same lanes and the
//! same order, so their results are identical bit for bit; the scalar path sums in the same
//! order without fusing, so its products round once more and it differs from them within
//! the bound the tests derive.

use crate::{Error, Result};
use std::sync::OnceLock;

/// A kernel path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Isa {
    /// Portable Rust for the compiler's baseline target (SSE2 on x86-64, which the
    /// compiler may use two lanes wide; NEON on aarch64), without fused multiply-adds.
    Scalar,
    /// x86-64 with AVX2, FMA and F16C (256-bit vectors).
    Avx2,
    /// x86-64 with AVX-512F (512-bit vectors), AVX2, FMA and F16C.
    Avx512,
    /// aarch64 with NEON (128-bit vectors; fused multiply-adds are part of the base ISA).
    Neon,
}

/// The environment variable that forces a path.
pub const ENV: &str = "BTF_SIMD";

impl Isa {
    /// Every path, fastest first (the order [`Isa::best`] tries them in).
    pub const ALL: [Isa; 4] = [Isa::Avx512, Isa::Avx2, Isa::Neon, Isa::Scalar];

    /// The name `BTF_SIMD` takes.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
            Isa::Neon => "neon",
        }
    }

    /// The CPU features the path needs, as `/proc/cpuinfo` spells them.
    pub fn features(self) -> &'static [&'static str] {
        match self {
            Isa::Scalar => &[],
            Isa::Avx2 => &["avx2", "fma", "f16c"],
            Isa::Avx512 => &["avx512f", "avx2", "fma", "f16c"],
            Isa::Neon => &["neon"],
        }
    }

    /// Whether this CPU can run the path.
    pub fn supported(self) -> bool {
        match self {
            Isa::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
                    && std::arch::is_x86_feature_detected!("f16c")
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => std::arch::is_x86_feature_detected!("avx512f") && Isa::Avx2.supported(),
            #[cfg(target_arch = "aarch64")]
            Isa::Neon => std::arch::is_aarch64_feature_detected!("neon"),
            #[allow(unreachable_patterns)] // every arm above may be compiled out
            _ => false,
        }
    }

    /// The fastest path this CPU supports.
    pub fn best() -> Isa {
        Isa::ALL.into_iter().find(|i| i.supported()).unwrap_or(Isa::Scalar)
    }

    /// Every path this CPU supports (the scalar one last).
    pub fn supported_all() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.supported()).collect()
    }

    /// The path a `BTF_SIMD` value asks for: `None` (unset), empty or `auto` gives
    /// [`Isa::best`]; a named path must be supported.
    pub fn choose(setting: Option<&str>) -> Result<Isa> {
        let s = setting.map(str::trim).unwrap_or("");
        if s.is_empty() || s.eq_ignore_ascii_case("auto") {
            return Ok(Isa::best());
        }
        let names = || Isa::ALL.map(Isa::name).join(", ");
        let Some(isa) = Isa::ALL.into_iter().find(|i| s.eq_ignore_ascii_case(i.name())) else {
            return Err(Error::Invalid(format!(
                "{ENV}={s}: not a kernel path (known: {}, auto)",
                names()
            )));
        };
        if !isa.supported() {
            let runnable: Vec<_> = Isa::supported_all().into_iter().map(Isa::name).collect();
            return Err(Error::Unsupported(format!(
                "{ENV}={s}: this CPU cannot run the {s} kernels (they need {}); it runs: {}",
                isa.features().join(", "),
                runnable.join(", ")
            )));
        }
        Ok(isa)
    }

    /// The path `BTF_SIMD` asks for (read at each call).
    pub fn from_env() -> Result<Isa> {
        Isa::choose(std::env::var(ENV).ok().as_deref())
    }

    /// The path the kernels use: [`Isa::from_env`], read once per process. Panics with its
    /// message when `BTF_SIMD` names a path this CPU cannot run (entry points that can
    /// return an error call [`Isa::from_env`] first).
    pub fn active() -> Isa {
        static ACTIVE: OnceLock<std::result::Result<Isa, String>> = OnceLock::new();
        match ACTIVE.get_or_init(|| Isa::from_env().map_err(|e| e.to_string())) {
            Ok(isa) => *isa,
            Err(e) => panic!("{e}"),
        }
    }
}

impl std::fmt::Display for Isa {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_is_the_best_path_and_names_parse() {
        assert_eq!(Isa::choose(None).unwrap(), Isa::best());
        assert_eq!(Isa::choose(Some("auto")).unwrap(), Isa::best());
        assert_eq!(Isa::choose(Some(" AUTO ")).unwrap(), Isa::best());
        assert_eq!(Isa::choose(Some("scalar")).unwrap(), Isa::Scalar);
        for isa in Isa::supported_all() {
            assert_eq!(Isa::choose(Some(isa.name())).unwrap(), isa);
        }
        assert!(Isa::best().supported() && Isa::Scalar.supported());
    }

    #[test]
    fn an_unsupported_or_unknown_path_is_an_error() {
        let err = Isa::choose(Some("sse9")).unwrap_err().to_string();
        assert!(err.contains("BTF_SIMD=sse9") && err.contains("avx2"), "{err}");
        // aarch64 and x86-64 each lack the other's path.
        let missing = if cfg!(target_arch = "aarch64") { Isa::Avx2 } else { Isa::Neon };
        let err = Isa::choose(Some(missing.name())).unwrap_err();
        assert!(matches!(err, Error::Unsupported(_)), "{err}");
        assert!(err.to_string().contains(missing.features()[0]), "{err}");
    }
}
