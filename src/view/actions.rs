//! What a key or a panel control asks the viewer to do, the key map, and applying an
//! action to the [`Viewer`] state. Mouse drags go straight to the viewer (`app.rs`).

use super::state::Viewer;
use btf_render::scene::{Evaluation, Shadows};
use winit::keyboard::{Key, NamedKey};

/// Degrees per environment-rotation key press.
pub const ENV_STEP_DEG: f32 = 15.0;
/// Exposure factor per key press.
pub const EXPOSURE_STEP: f32 = 1.25;

/// One request from the keyboard or the panel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Shadows none → volume → map.
    CycleShadows,
    /// Set the shadow technique.
    Shadows(Shadows),
    /// Smooth shadow boundary offset α between the scene's value and 0°.
    ToggleTerminator,
    /// Set α (degrees).
    Terminator(f32),
    /// Four-nearest ↔ nearest blending.
    ToggleBlending,
    /// Per-pixel ↔ per-vertex.
    ToggleEvaluation,
    /// Set the evaluation mode.
    Evaluation(Evaluation),
    /// Add PCA components.
    Components(i64),
    /// Fabric by index (0 = as in the scene).
    Fabric(usize),
    /// The next fabric.
    NextFabric,
    /// Environment by index.
    Env(usize),
    /// The next environment.
    NextEnv,
    /// Turn the environment by degrees.
    RotateEnv(f32),
    /// Multiply the exposure.
    Exposure(f32),
    /// Write the last frame as a PNG.
    Screenshot,
    /// Back to the scene's camera.
    ResetCamera,
    /// Hide or show the panel.
    TogglePanel,
    /// Close the viewer.
    Quit,
}

/// The action bound to a key, if any.
pub fn for_key(key: &Key) -> Option<Action> {
    match key {
        Key::Named(NamedKey::Escape) => Some(Action::Quit),
        Key::Named(NamedKey::F12) => Some(Action::Screenshot),
        Key::Named(NamedKey::ArrowLeft) => Some(Action::RotateEnv(-ENV_STEP_DEG)),
        Key::Named(NamedKey::ArrowRight) => Some(Action::RotateEnv(ENV_STEP_DEG)),
        Key::Character(c) => match c.as_str() {
            "q" => Some(Action::Quit),
            "p" => Some(Action::Screenshot),
            "[" => Some(Action::RotateEnv(-ENV_STEP_DEG)),
            "]" => Some(Action::RotateEnv(ENV_STEP_DEG)),
            "e" => Some(Action::NextEnv),
            "f" => Some(Action::NextFabric),
            "+" | "=" => Some(Action::Exposure(EXPOSURE_STEP)),
            "-" => Some(Action::Exposure(1.0 / EXPOSURE_STEP)),
            "s" => Some(Action::CycleShadows),
            "t" => Some(Action::ToggleTerminator),
            "b" => Some(Action::ToggleBlending),
            "v" => Some(Action::ToggleEvaluation),
            "c" => Some(Action::Components(1)),
            "x" => Some(Action::Components(-1)),
            "r" => Some(Action::ResetCamera),
            "h" => Some(Action::TogglePanel),
            _ => None,
        },
        _ => None,
    }
}

/// The key help shown in the panel (and the README).
pub const KEYS: &[(&str, &str)] = &[
    ("left drag", "turn the garment (orbit)"),
    ("right drag", "move the light(s)"),
    ("middle / shift+left drag", "pan"),
    ("wheel", "zoom"),
    ("[ ] or Left/Right arrow", "rotate the environment 15°"),
    ("e / f", "next environment / fabric"),
    ("+ / -", "exposure ×1.25 / ÷1.25"),
    ("s t b v", "shadows, terminator α, blending, evaluation"),
    ("c / x", "one PCA component more / fewer"),
    ("p or F12", "screenshot (PNG of the frame)"),
    ("r / h", "reset camera / hide panel"),
    ("q or Esc", "quit"),
];

/// Applies `action`; `Screenshot`, `TogglePanel` and `Quit` belong to the window and are
/// ignored here.
pub fn apply(v: &mut Viewer, action: Action) {
    let fabric = v.fabric;
    match action {
        Action::CycleShadows => v.cycle_shadows(),
        Action::Shadows(s) => {
            let mut fx = v.effects.clone();
            fx.shadows = s;
            v.set_effects(fx, fabric);
        }
        Action::ToggleTerminator => v.toggle_terminator(),
        Action::Terminator(deg) => v.set_terminator(deg),
        Action::ToggleBlending => v.toggle_blending(),
        Action::ToggleEvaluation => v.toggle_evaluation(),
        Action::Evaluation(e) => {
            let mut fx = v.effects.clone();
            fx.evaluation = e;
            v.set_effects(fx, fabric);
        }
        Action::Components(d) => v.step_components(d),
        Action::Fabric(i) => v.set_effects(v.effects.clone(), i),
        Action::NextFabric => {
            let n = v.fabric_names().len();
            v.set_effects(v.effects.clone(), (fabric + 1) % n);
        }
        Action::Env(i) => v.select_env(i),
        Action::NextEnv => {
            if let Some(i) = v.env.next_index() {
                v.select_env(i);
            }
        }
        Action::RotateEnv(d) => v.rotate_env(d),
        Action::Exposure(f) => v.exposure = (v.exposure * f).clamp(1e-4, 1e4),
        Action::ResetCamera => v.reset_camera(),
        Action::Screenshot | Action::TogglePanel | Action::Quit => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_map_to_actions() {
        let ch = |s: &str| for_key(&Key::Character(s.into()));
        assert_eq!(ch("]"), Some(Action::RotateEnv(ENV_STEP_DEG)));
        assert_eq!(ch("p"), Some(Action::Screenshot));
        assert_eq!(ch("q"), Some(Action::Quit));
        assert_eq!(ch("z"), None);
        assert_eq!(for_key(&Key::Named(NamedKey::Escape)), Some(Action::Quit));
        // Every single-character key in the help is bound.
        for (keys, _) in KEYS {
            for k in keys.split([' ', '/']).filter(|k| k.len() == 1) {
                assert!(ch(k).is_some(), "key {k} in the help is unbound");
            }
        }
    }
}
