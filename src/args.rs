//! Arguments shared by several commands: the scene every rendering command loads
//! ([`SceneArgs`]: load, override the frame size, validate — in one place, with the key at
//! fault named), and the comma-separated number lists of `--roi`, `--albedo`, `--pose-noise`
//! and the like ([`numbers`]), and the closed sets of choices every command shares
//! ([`choices!`]: clap value enums, so `--help` lists them and a typo gets clap's "possible
//! values" error). The flag naming scheme they follow is written down in `docs/cli.md`.

use anyhow::{Context, Result, bail};
use btf_render::Scene;
use std::path::PathBuf;

/// Declares a clap value enum whose values are spelled as given, with `as_str` (the
/// spelling, so code that matched the old string options reads the same) and `Display`.
macro_rules! choices {
    ($(#[$m:meta])* $name:ident { $($(#[$vm:meta])* $variant:ident = $text:literal),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
        pub enum $name {
            $($(#[$vm])* #[value(name = $text)] $variant),+
        }
        impl $name {
            /// The value as written on the command line.
            #[allow(dead_code)]
            pub fn as_str(self) -> &'static str {
                match self { $($name::$variant => $text),+ }
            }
        }
        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.as_str())
            }
        }
    };
}
pub(crate) use choices;

choices! {
    /// Element type of a BTF store (`--dtype`).
    Dtype {
        /// 32-bit float (exact).
        F32 = "f32",
        /// 16-bit float (half the bytes, ~3 significant digits).
        F16 = "f16",
    }
}

impl Dtype {
    /// The store's element type.
    pub fn dtype(self) -> btf_core::zarr::DType {
        match self {
            Dtype::F32 => btf_core::zarr::DType::F32,
            Dtype::F16 => btf_core::zarr::DType::F16,
        }
    }
}

choices! {
    /// Storage of eigentextures in an eigen store (`--quantization`).
    Quantization {
        /// Half precision per value.
        F16 = "f16",
        /// 8 bits per value with a per-component scale and offset.
        U8 = "u8",
    }
}

impl Quantization {
    /// The eigen store's quantization.
    pub fn quantization(self) -> btf_core::eigen::Quantization {
        match self {
            Quantization::F16 => btf_core::eigen::Quantization::F16,
            Quantization::U8 => btf_core::eigen::Quantization::U8,
        }
    }
}

choices! {
    /// Arithmetic of the compressor's Gram matrices (`btf compress --gram`).
    Gram {
        /// f32 for f16 stores, f64 for f32 ones.
        Auto = "auto",
        /// f64 throughout.
        F64 = "f64",
        /// f32 within chunks of 64 columns, f64 across them.
        F32 = "f32",
    }
}

choices! {
    /// Chunk codec of a store's bulk arrays (`--codec`: a BTF store's normtextures, an eigen
    /// store's means and eigentextures).
    Codec {
        /// Byte shuffle, then zstd level 1 (blosc): about half the bytes of a BTF store, 30 %
        /// fewer for an eigen store.
        Blosc = "blosc",
        /// Raw chunks with their checksum: no encoding or decoding time, a larger store.
        Raw = "none",
    }
}

impl Codec {
    /// The normtextures' codec of a BTF store.
    pub fn btf(self) -> btf_core::zarr::Compression {
        match self {
            Codec::Blosc => btf_core::zarr::Compression::DEFAULT,
            Codec::Raw => btf_core::zarr::Compression::None,
        }
    }

    /// The means' and eigentextures' codec of an eigen store.
    pub fn eigen(self) -> btf_core::zarr::Compression {
        match self {
            Codec::Blosc => btf_core::zarr::Compression::FAST,
            Codec::Raw => btf_core::zarr::Compression::None,
        }
    }
}

impl Gram {
    /// The compressor's setting.
    pub fn precision(self) -> btf_core::pca::GramPrecision {
        match self {
            Gram::Auto => btf_core::pca::GramPrecision::Auto,
            Gram::F64 => btf_core::pca::GramPrecision::F64,
            Gram::F32 => btf_core::pca::GramPrecision::F32,
        }
    }
}

choices! {
    /// Blending of the nearest sampled directions (`--blend`, `--light-interp`).
    Blend {
        /// The four nearest directions, weighted ([S03 eq. 3, 5]).
        Four = "four",
        /// The nearest direction only.
        Nearest = "nearest",
    }
}

impl Blend {
    /// The interpolation mode.
    pub fn mode(self) -> btf_core::interp::InterpMode {
        match self {
            Blend::Four => btf_core::interp::InterpMode::Four,
            Blend::Nearest => btf_core::interp::InterpMode::Nearest,
        }
    }
}

choices! {
    /// A synthetic mesostructure material (`datasets::MaterialKind`).
    Material {
        /// Flat Lambertian with a patterned albedo (the analytic validation case).
        Lambert = "lambert",
        /// Rounded wales with a sheen pile (anisotropic).
        Corduroy = "corduroy",
        /// Stockinette knit of yarn tubes.
        Knit = "knit",
        /// Plain weave of two yarn colours.
        Woven = "woven",
        /// Embossed glossy paint.
        Wallpaper = "wallpaper",
        /// Fractal stone relief.
        Stone = "stone",
    }
}

/// A scene file and the overrides every rendering command takes (`#[command(flatten)]`).
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene description (TOML).
    pub scene: PathBuf,
    /// Image width (overrides the scene).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (overrides the scene).
    #[arg(long)]
    pub height: Option<u32>,
}

impl SceneArgs {
    /// The scene with the overrides applied, not yet validated (for commands that add to
    /// it first, as `btf relight` adds its environment light).
    pub fn load_unvalidated(&self) -> Result<Scene> {
        let mut scene = Scene::load(&self.scene)?;
        if let Some(w) = self.width {
            scene.output.width = w;
        }
        if let Some(h) = self.height {
            scene.output.height = h;
        }
        Ok(scene)
    }

    /// The scene with the overrides applied and validated (keys named on error).
    pub fn load(&self) -> Result<Scene> {
        let scene = self.load_unvalidated()?;
        scene.validate(&self.scene)?;
        Ok(scene)
    }
}

/// `--shard I/N` / `--shard-count N`: which part of a job this process does (issue #23).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ShardArgs {
    /// Do shard I of N (0-based) of the job, writing only its own part into the shared
    /// output; every shard must be given the same inputs and parameters. Finish with
    /// `btf finalize OUT`.
    #[arg(long, value_name = "I/N", conflicts_with = "shard_count")]
    pub shard: Option<String>,
    /// Split the job into N shards and take this process's index from
    /// JOB_COMPLETION_INDEX (Kubernetes Indexed Job) or SLURM_ARRAY_TASK_ID (Slurm array).
    #[arg(long, value_name = "N")]
    pub shard_count: Option<usize>,
}

impl ShardArgs {
    /// The shard asked for, if any.
    pub fn shard(&self) -> Result<Option<btf_core::shard::Shard>> {
        use btf_core::shard::Shard;
        Ok(match (&self.shard, self.shard_count) {
            (Some(s), _) => Some(Shard::parse(s)?),
            (None, Some(n)) => Some(Shard::from_env(n, |k| std::env::var(k).ok())?),
            (None, None) => None,
        })
    }
}

/// Parses `N` comma-separated numbers of option `what` (`"--roi"`), naming the option and
/// the text on error.
pub fn numbers<T: std::str::FromStr, const N: usize>(s: &str, what: &str) -> Result<[T; N]>
where
    T::Err: std::error::Error + Send + Sync + 'static,
{
    let v: Vec<T> = s
        .split(',')
        .map(|x| x.trim().parse::<T>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("{what} '{s}': expected {N} comma-separated numbers"))?;
    match <[T; N]>::try_from(v) {
        Ok(a) => Ok(a),
        Err(v) => bail!("{what} '{s}': expected {N} comma-separated numbers, got {}", v.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_and_errors_name_the_option() {
        assert_eq!(numbers::<f64, 3>("0.1, 0.2,0.3", "--albedo").unwrap(), [0.1, 0.2, 0.3]);
        let e = numbers::<f64, 2>("1,2,3", "--pose-noise").unwrap_err().to_string();
        assert!(e.contains("--pose-noise '1,2,3'") && e.contains("got 3"), "{e}");
        let e = format!("{:#}", numbers::<u32, 2>("1,x", "--resolution").unwrap_err());
        assert!(e.contains("--resolution '1,x'"), "{e}");
    }
}
