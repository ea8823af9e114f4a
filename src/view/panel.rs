//! The on-screen panel of `btf view` (egui, immediate mode): frame time and each pass's
//! cost, the cost of the last interaction of each kind, fabric and environment choice,
//! environment rotation, exposure, the effect switches, errors, and the key help. Controls
//! only produce [`Action`]s; the window applies them after the panel is drawn.
//!
//! The layout does not move while one works with it: every line of the timing block is
//! there from the first frame (a dash until a figure exists), long lines are truncated to
//! the panel's width instead of widening it, and only ASCII, Latin-1 and Greek glyphs are
//! used (egui's built-in fonts have no arrows).

use super::actions::{Action, KEYS};
use super::state::{Change, Latency, Viewer};
use btf_render::scene::{Evaluation, Shadows};
use egui::{Color32, RichText};
use std::collections::BTreeMap;

/// Width of the panel in points.
pub const WIDTH_PT: f32 = 250.0;

/// The last latency of each kind of interaction (for the panel).
#[derive(Debug, Default)]
pub struct LatencyLog {
    by_kind: BTreeMap<&'static str, Latency>,
}

impl LatencyLog {
    /// Records the cost of a frame.
    pub fn record(&mut self, l: Latency) {
        if l.change != Change::Start {
            self.by_kind.insert(l.change.name(), l);
        }
    }
}

/// Draws the panel; returns the actions its controls asked for.
pub fn show(ui: &mut egui::Ui, v: &Viewer, log: &LatencyLog, adapter: &str) -> Vec<Action> {
    let mut out = Vec::new();
    egui::Panel::left("btf-view-panel").exact_size(WIDTH_PT).resizable(false).show(ui, |ui| {
        egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
            ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Truncate);
            ui.heading("btf view");
            ui.label(RichText::new(adapter).small());
            timing(ui, v, log);
            ui.separator();
            fabric_and_env(ui, v, &mut out);
            ui.separator();
            effects(ui, v, &mut out);
            errors(ui, v);
            ui.collapsing("keys and mouse", |ui| {
                for (k, what) in KEYS {
                    ui.label(format!("{k}: {what}"));
                }
            });
        });
    });
    out
}

/// The kinds of interaction the latency block always lists, in this order.
const KINDS: [Change; 5] =
    [Change::Camera, Change::Light, Change::EnvRotation, Change::EnvSwap, Change::Rebuild];

fn timing(ui: &mut egui::Ui, v: &Viewer, log: &LatencyLog) {
    let frame = v.last.map_or("-".to_string(), |l| format!("{:.1} ms", l.total_ms()));
    let size = v
        .shown
        .as_ref()
        .map_or("-".to_string(), |s| format!("{} x {} px", s.texture.width(), s.texture.height()));
    ui.monospace(format!("frame {frame:>10}")).on_hover_text(
        "time from the last change to the finished frame (work before rendering + rendering)",
    );
    ui.monospace(format!("size  {size:>10}"))
        .on_hover_text("frames are rendered at the size of the window's frame area");
    ui.collapsing("passes of the last frame", |ui| {
        if let Some(s) = &v.shown {
            ui.label(RichText::new(format!("timed by {}", s.stats.timing)).small());
            for p in &s.stats.passes {
                ui.monospace(format!("{:>7.2} ms  {}", p.ms, p.name));
            }
        }
    });
    ui.label("last change of each kind, ms:");
    for kind in KINDS {
        let line = match log.by_kind.get(kind.name()) {
            Some(l) => format!("{:<12}{:>9.1}", short_name(kind), l.total_ms()),
            None => format!("{:<12}{:>9}", short_name(kind), "-"),
        };
        let hover = log.by_kind.get(kind.name()).map_or_else(
            || format!("{}: not done yet", kind.name()),
            |l| {
                format!(
                    "{}: {:.1} ms update + {:.1} ms render",
                    kind.name(),
                    l.update_ms,
                    l.render_ms
                )
            },
        );
        ui.monospace(line).on_hover_text(hover);
    }
}

/// A label of at most 12 characters for the latency lines.
fn short_name(kind: Change) -> &'static str {
    match kind {
        Change::Camera => "camera",
        Change::Light => "light",
        Change::EnvRotation => "env. turn",
        Change::EnvSwap => "env. swap",
        Change::Rebuild => "rebuild",
        Change::Start => "start",
    }
}

fn fabric_and_env(ui: &mut egui::Ui, v: &Viewer, out: &mut Vec<Action>) {
    ui.label("fabric");
    for (i, name) in v.fabric_names().iter().enumerate() {
        if ui.radio(v.fabric == i, name).clicked() && v.fabric != i {
            out.push(Action::Fabric(i));
        }
    }
    ui.label("environment");
    if v.env.files.is_empty() {
        ui.label(RichText::new("none (add with --env FILE)").italics());
    }
    for i in 0..v.env.files.len() {
        if ui.radio(v.env.current == Some(i), v.env.name(i)).clicked() {
            out.push(Action::Env(i));
        }
    }
    if let Some(e) = &v.env.error {
        ui.colored_label(Color32::LIGHT_RED, e);
    }
    if v.env.current.is_some() && !v.env.lighting {
        ui.label(
            RichText::new("not lighting the garment: the scene has no environment light").small(),
        );
    }
    let mut rot = v.env.rotation_deg;
    let slider = egui::Slider::new(&mut rot, 0.0..=360.0).suffix("°").text("env. rotation");
    if ui
        .add(slider)
        .on_hover_text(
            "the environment's absolute turn about the up axis (the scene's value at the start)",
        )
        .changed()
    {
        out.push(Action::RotateEnv(rot - v.env.rotation_deg));
    }
    if v.env.lighting {
        let how = if v.env.auto_exposure { "auto" } else { "fixed" };
        ui.label(format!("environment light f = {:.4} ({how})", v.env.light_exposure))
            .on_hover_text("the factor on the map's radiance; auto gives every map the horizontal irradiance of the scene's own environment (--env-exposure)");
    }
    let mut ev = v.exposure.log2();
    let slider = egui::Slider::new(&mut ev, -8.0..=8.0).text("display EV");
    if ui
        .add(slider)
        .on_hover_text(format!(
            "display exposure in stops: pixels are multiplied by 2^EV = {:.3} before sRGB encoding (the scene's output.exposure at the start)",
            v.exposure
        ))
        .changed()
    {
        out.push(Action::Exposure(2f32.powf(ev) / v.exposure));
    }
}

fn effects(ui: &mut egui::Ui, v: &Viewer, out: &mut Vec<Action>) {
    let fx = &v.effects;
    ui.horizontal(|ui| {
        ui.label("shadows");
        for (s, name) in
            [(Shadows::None, "none"), (Shadows::Volume, "volume"), (Shadows::Map, "map")]
        {
            if ui.radio(fx.shadows == s, name).clicked() && fx.shadows != s {
                out.push(Action::Shadows(s));
            }
        }
    });
    let mut alpha = fx.terminator_deg;
    if ui.add(egui::Slider::new(&mut alpha, 0.0..=45.0).text("terminator α °")).changed() {
        out.push(Action::Terminator(alpha));
    }
    ui.horizontal(|ui| {
        for (e, name) in
            [(Evaluation::PerPixel, "per pixel"), (Evaluation::PerVertex, "per vertex")]
        {
            if ui.radio(fx.evaluation == e, name).clicked() && fx.evaluation != e {
                out.push(Action::Evaluation(e));
            }
        }
    });
    let mut four = fx.view_blend == btf_core::InterpMode::Four;
    if ui.checkbox(&mut four, "four-nearest blending").changed() {
        out.push(Action::ToggleBlending);
    }
    ui.horizontal(|ui| {
        let c = fx.components.map_or("all".to_string(), |c| c.to_string());
        ui.label(format!("components {c}"));
        if ui.button("-").clicked() {
            out.push(Action::Components(-1));
        }
        if ui.button("+").clicked() {
            out.push(Action::Components(1));
        }
    });
}

fn errors(ui: &mut egui::Ui, v: &Viewer) {
    if v.errors.is_empty() {
        return;
    }
    ui.separator();
    for e in v.errors.iter().rev().take(4) {
        ui.colored_label(Color32::LIGHT_RED, e);
    }
}
