//! The on-screen panel of `btf view` (egui, immediate mode): frame time and each pass's
//! cost, the cost of the last interaction of each kind, fabric and environment choice,
//! environment rotation, exposure, the effect switches, errors, and the key help. Controls
//! only produce [`Action`]s; the window applies them after the panel is drawn.

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
        egui::ScrollArea::vertical().show(ui, |ui| {
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

fn timing(ui: &mut egui::Ui, v: &Viewer, log: &LatencyLog) {
    if let Some(l) = &v.last {
        ui.monospace(format!("frame {:7.1} ms ({})", l.total_ms(), l.change.name()));
    }
    if let Some(s) = &v.shown {
        let (w, h) = (s.texture.width(), s.texture.height());
        ui.label(format!("{w}×{h}, passes ({}):", s.stats.timing));
        for p in &s.stats.passes {
            ui.monospace(format!("{:>7.2} ms  {}", p.ms, p.name));
        }
    }
    if !log.by_kind.is_empty() {
        ui.label("last interaction (update + render):");
        for (name, l) in &log.by_kind {
            ui.monospace(format!(
                "{:>7.1} = {:.1} + {:.1}  {name}",
                l.total_ms(),
                l.update_ms,
                l.render_ms
            ));
        }
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
    if ui.add(egui::Slider::new(&mut rot, 0.0..=360.0).text("rotation °")).changed() {
        out.push(Action::RotateEnv(rot - v.env.rotation_deg));
    }
    let mut ev = v.exposure.log2();
    if ui.add(egui::Slider::new(&mut ev, -8.0..=8.0).text("exposure EV")).changed() {
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
        if ui.button("−").clicked() {
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
