//! Arguments shared by several commands: the scene every rendering command loads
//! ([`SceneArgs`]: load, override the frame size, validate — in one place, with the key at
//! fault named), and the comma-separated number lists of `--roi`, `--albedo`, `--pose-noise`
//! and the like ([`numbers`]).

use anyhow::{Context, Result, bail};
use btf_render::Scene;
use std::path::PathBuf;

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
