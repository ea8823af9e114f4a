//! End-to-end tests of `btf view` as a person uses it: the real binary in a window on a
//! virtual X server (Xvfb) rendering on lavapipe, driven by real synthetic X input (xdotool
//! through XTEST), its screenshot key writing PNGs that are measured, and a window-manager
//! close (`WM_DELETE_WINDOW`). Also the headless turntable export and latency benchmark.
//!
//! Without Xvfb, xdotool or a GPU adapter the tests skip, unless `BTF_REQUIRE_GPU=1` (CI),
//! where they fail.

use crate::common;

use common::Dir;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

fn required() -> bool {
    std::env::var("BTF_REQUIRE_GPU").as_deref() == Ok("1")
}

/// Skips (or fails under `BTF_REQUIRE_GPU=1`) with `why`.
fn skip(test: &str, why: &str) {
    assert!(!required(), "{test}: BTF_REQUIRE_GPU=1 but {why}");
    eprintln!("{test}: skipped, {why}");
}

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A shirt in a small synthetic corduroy, under a point light, 320×240, on a purple
/// background (sRGB (108, 0, 108) at exposure 1.5, a colour the beige fabric never takes);
/// two environments and one missing file (listed first, so start-up meets it).
fn garment_scene(d: &Dir) -> PathBuf {
    d.ok(&["synth", "material", "--kind", "corduroy", "--size", "8", "-o", "m.btf"]);
    d.ok(&["compress", "m.btf", "-c", "4", "-o", "m.eig"]);
    d.ok(&["synth", "mesh", "--kind", "shirt", "-o", "shirt.obj"]);
    d.ok(&["synth", "env", "--kind", "sky", "--width", "64", "-o", "sky.exr"]);
    d.ok(&["synth", "env", "--kind", "studio", "--width", "64", "-o", "studio.exr"]);
    let studio = "[[lights]]\nkind = \"environment\"\npath = \"studio.exr\"\nexposure = 0.5\n\
                  visibility_res = 8\neigenweightsets = { rotations = 12, components = 4 }\n\
                  cache_dir = \"cache\"\n";
    let scene = shirt_scene(320, 240, [0.3, -1.5, 0.5], [-0.9, -1.6, 1.5], 12.0, studio);
    let path = d.path("scene.toml");
    std::fs::write(&path, scene).unwrap();
    path
}

/// sRGB level of the background's red and blue: linear 0.1 × exposure 1.5.
const BACKGROUND_SRGB: u8 = 108;

/// An 8-bit RGB image.
struct Shot {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl Shot {
    fn load(path: &Path) -> Shot {
        let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
        Shot { w: img.width() as usize, h: img.height() as usize, rgb: img.into_raw() }
    }
    /// Pixels of the garment: not the background colour (±2 levels).
    fn mask(&self) -> Vec<bool> {
        let bg = [BACKGROUND_SRGB, 0, BACKGROUND_SRGB];
        self.rgb.chunks_exact(3).map(|p| (0..3).any(|k| p[k].abs_diff(bg[k]) > 2)).collect()
    }
    fn coverage(&self) -> f64 {
        let m = self.mask();
        m.iter().filter(|&&b| b).count() as f64 / m.len() as f64
    }
    /// Fraction of pixels whose largest channel difference exceeds `tol`.
    fn changed(&self, other: &Shot, tol: u8) -> f64 {
        let n = self.w * self.h;
        let c = (0..n)
            .filter(|&i| (0..3).any(|k| self.rgb[3 * i + k].abs_diff(other.rgb[3 * i + k]) > tol))
            .count();
        c as f64 / n as f64
    }
    /// Fraction of pixels inside one silhouette and outside the other.
    fn silhouette_xor(&self, other: &Shot) -> f64 {
        let (a, b) = (self.mask(), other.mask());
        a.iter().zip(&b).filter(|(x, y)| x != y).count() as f64 / a.len() as f64
    }
    /// Mean level (0–255, over channels) of the garment's pixels.
    fn garment_mean(&self) -> f64 {
        let m = self.mask();
        let (mut sum, mut n) = (0u64, 0u64);
        for (i, _) in m.iter().enumerate().filter(|(_, g)| **g) {
            sum += (0..3).map(|k| self.rgb[3 * i + k] as u64).sum::<u64>();
            n += 3;
        }
        sum as f64 / n.max(1) as f64
    }
    /// Mean absolute difference (0–255) over pixels of the garment in both images.
    fn shading_difference(&self, other: &Shot) -> f64 {
        let (a, b) = (self.mask(), other.mask());
        let (mut sum, mut n) = (0u64, 0u64);
        for i in 0..a.len() {
            if a[i] && b[i] {
                sum += (0..3)
                    .map(|k| self.rgb[3 * i + k].abs_diff(other.rgb[3 * i + k]) as u64)
                    .sum::<u64>();
                n += 3;
            }
        }
        sum as f64 / n.max(1) as f64
    }
}

/// A virtual X server on a free display, stopped on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        let n = (90..190)
            .find(|n| {
                !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
                    && !Path::new(&format!("/tmp/.X{n}-lock")).exists()
            })
            .expect("a free X display number");
        let display = format!(":{n}");
        let child = Command::new("Xvfb")
            .args([&display, "-screen", "0", "1280x800x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let t = Instant::now();
        while !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
            assert!(t.elapsed() < Duration::from_secs(10), "Xvfb {display} did not come up");
            std::thread::sleep(Duration::from_millis(50));
        }
        Xvfb { child, display }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The viewer process and its stdout lines.
struct Viewer {
    child: Child,
    lines: Receiver<String>,
    display: String,
    /// The last `frame …` line [`settle`] saw.
    last_frame: std::cell::RefCell<String>,
}

/// The cumulative `read_back_bytes=N` of a `frame …` log line.
fn read_back_bytes(frame_line: &str) -> u64 {
    let field = frame_line.split(' ').find_map(|t| t.strip_prefix("read_back_bytes="));
    field.unwrap_or_else(|| panic!("no read_back_bytes in {frame_line:?}")).parse().unwrap()
}

impl Viewer {
    fn start(d: &Dir, display: &str, scene: &Path) -> Viewer {
        let envs = ["--env", "missing.exr", "--env", "sky.exr", "--env", "studio.exr"];
        Viewer::spawn(d, display, scene, &envs)
    }

    fn spawn(d: &Dir, display: &str, scene: &Path, extra: &[&str]) -> Viewer {
        let mut child = Command::new(env!("CARGO_BIN_EXE_btf"))
            .args(["view", scene.to_str().unwrap(), "--log", "--shots", "shots"])
            // a small window: lavapipe renders every frame on the CPU
            .args(["--width", "320", "--height", "240"])
            .args(extra)
            .current_dir(d.tmp.path())
            .env("DISPLAY", display)
            .env("BTF_NO_PROGRESS", "1")
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("btf view starts");
        let out = child.stdout.take().unwrap();
        let (tx, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                eprintln!("viewer: {line}");
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Viewer { child, lines, display: display.to_string(), last_frame: Default::default() }
    }

    /// The next line containing `pat` (panics after `secs`).
    fn wait_for(&self, pat: &str, secs: u64) -> String {
        let deadline = Instant::now() + Duration::from_secs(secs);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) if l.contains(pat) => return l,
                Ok(_) => {}
                Err(e) => panic!("no line with {pat:?} within {secs} s ({e})"),
            }
        }
    }

    fn xdotool(&self, args: &[&str]) {
        let o = Command::new("xdotool").args(args).env("DISPLAY", &self.display).output().unwrap();
        assert!(o.status.success(), "xdotool {args:?}: {}", String::from_utf8_lossy(&o.stderr));
    }

    /// Presses the screenshot key and loads the PNG it reports.
    fn shot(&self, d: &Dir) -> Shot {
        self.xdotool(&["key", "p"]);
        let line = self.wait_for("screenshot ", 20);
        Shot::load(&d.tmp.path().join(line.trim_start_matches("screenshot ")))
    }

    /// A real drag with `button` from `(x, y)` by `(dx, 0)` in 12 steps (window pixels).
    fn drag(&self, window: &str, button: &str, (x, y): (i32, i32), dx: i32) {
        let mut args: Vec<String> =
            ["mousemove", "--window", window, &x.to_string(), &y.to_string()]
                .map(String::from)
                .to_vec();
        args.extend(["mousedown".into(), button.into()]);
        for k in 1..=12 {
            let xk = x + dx * k / 12;
            args.extend(["sleep", "0.03", "mousemove", "--window", window].map(String::from));
            args.extend([xk.to_string(), y.to_string()]);
        }
        args.extend(["mouseup".into(), button.into()]);
        self.xdotool(&args.iter().map(String::as_str).collect::<Vec<_>>());
    }
}

/// Reads the viewer's lines until a frame rendered at the size of the latest layout's frame
/// rectangle has been logged (the first frame is rendered for the whole window, the next
/// for the area the panel leaves): `(window id, first frame line, layout)`, or `None` after
/// 60 s.
fn settle(v: &Viewer) -> Option<(String, String, Vec<f32>)> {
    let (mut window, mut first, mut layout) = (String::new(), String::new(), Vec::new());
    let mut size = String::new();
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let l = v.lines.recv_timeout(deadline.saturating_duration_since(Instant::now())).ok()?;
        if l.starts_with("window ") {
            window = l.split(' ').nth(1).unwrap().into();
        } else if l.starts_with("layout ") {
            layout = l.split(' ').skip(1).map(|t| t.parse().unwrap()).collect();
        } else if l.starts_with("frame ") {
            if first.is_empty() {
                first = l.clone();
            }
            size = l.split(' ').nth(2).unwrap_or_default().to_string();
            *v.last_frame.borrow_mut() = l.clone();
        }
        if !window.is_empty()
            && layout.len() == 4
            && size == format!("size={}x{}", layout[2], layout[3])
        {
            return Some((window, first, layout));
        }
    }
}

/// Sends `WM_DELETE_WINDOW`, as a window manager's close button does.
fn close_window(display: &str, window: u32) {
    use x11rb::protocol::xproto::{ClientMessageEvent, ConnectionExt, EventMask};
    let (conn, _) = x11rb::connect(Some(display)).expect("X connection");
    let atom = |name: &[u8]| conn.intern_atom(false, name).unwrap().reply().unwrap().atom;
    let (protocols, delete) = (atom(b"WM_PROTOCOLS"), atom(b"WM_DELETE_WINDOW"));
    let ev = ClientMessageEvent::new(32, window, protocols, [delete, 0, 0, 0, 0]);
    conn.send_event(false, window, EventMask::NO_EVENT, ev).unwrap().check().unwrap();
    // A round trip, so the server has handled the request before the connection closes.
    conn.get_input_focus().unwrap().reply().unwrap();
}

#[test]
fn window_draws_turns_lights_and_closes() {
    let test = "window_draws_turns_lights_and_closes";
    for tool in ["Xvfb", "xdotool"] {
        if !have(tool) {
            return skip(test, &format!("{tool} is not installed (apt-get install xvfb xdotool)"));
        }
    }
    let t0 = Instant::now();
    let d = Dir::new();
    let scene = garment_scene(&d);
    let x = Xvfb::start();
    let mut v = Viewer::start(&d, &x.display, &scene);
    let Some((window, first, r)) = settle(&v) else {
        let status = v.child.try_wait().unwrap();
        return skip(test, &format!("the viewer showed no frame (exit {status:?})"));
    };
    // The missing environment (first in the list) is an error in the panel, not a crash.
    assert!(first.contains("env_error=Some(") && first.contains("missing.exr"), "{first}");
    // The frame's rectangle in the window (right of the panel): drags start at its centre.
    let centre = ((r[0] + r[2] / 2.0) as i32, (r[1] + r[3] / 2.0) as i32);
    let (cx, cy) = (centre.0.to_string(), centre.1.to_string());
    v.xdotool(&["mousemove", "--window", &window, &cx, &cy]);
    v.xdotool(&["windowfocus", "--sync", &window]);

    let start = v.shot(&d);
    // The frame is rendered at the size of the window's frame area, not the scene's.
    assert_eq!((start.w, start.h), (r[2] as usize, r[3] as usize), "{r:?}");
    let coverage = start.coverage();
    eprintln!("garment coverage {coverage:.3}");
    assert!(coverage > 0.12, "garment covers {coverage:.3} of the frame");

    // A left drag of 150 px turns the garment by 60°.
    v.drag(&window, "1", centre, 150);
    let turned = v.shot(&d);
    let (changed, xor) = (turned.changed(&start, 8), turned.silhouette_xor(&start));
    eprintln!("drag: changed {changed:.3}, silhouette xor {xor:.3}");
    assert!(changed > 0.08 && xor > 0.03, "drag changed {changed:.3}, silhouette {xor:.3}");

    // A right drag moves the light: shading changes, the silhouette does not.
    v.drag(&window, "3", centre, -120);
    let relit = v.shot(&d);
    let (xor, shading) = (relit.silhouette_xor(&turned), relit.shading_difference(&turned));
    eprintln!("light drag: silhouette xor {xor:.4}, shading {shading:.2}/255");
    assert!(xor == 0.0 && shading > 2.0, "light drag: xor {xor:.4}, shading {shading:.2}");

    // Next environment (the sky) loads; rotating it by 60°.
    v.xdotool(&["key", "e"]);
    let line = v.wait_for("change=EnvSwap", 20);
    assert!(line.contains("env=Some(1)") && line.contains("env_error=None"), "{line}");
    assert!(line.contains("env_lighting=true"), "swap did not reach the environment light: {line}");
    let before = v.shot(&d);
    // Auto-exposure: the sky is lit at the factor that gives a horizontal surface the
    // studio's irradiance at the scene's 0.5, f = 0.5 · E_h(studio) / E_h(sky), so the
    // garment keeps its brightness (within a factor 2 of the studio-lit frame: the maps'
    // light comes from other directions) instead of following the maps' scales.
    let f: f64 = line.split(' ').find_map(|t| t.strip_prefix("env_f=")).unwrap().parse().unwrap();
    let unit = |m: &str| btf_image::EnvMap::load(&d.path(m)).unwrap().unit_irradiance_exposure();
    let expect = 0.5 * unit("sky.exr") / unit("studio.exr");
    assert!((f / expect - 1.0).abs() < 1e-5, "sky's light factor {f}, expected {expect}");
    let (b0, b1) = (relit.garment_mean(), before.garment_mean());
    eprintln!("garment mean level: studio {b0:.1}, sky {b1:.1} (env_f {f})");
    assert!(b1 / b0 > 0.5 && b1 / b0 < 2.0 && b1 < 230.0, "studio {b0:.1} → sky {b1:.1}");
    for _ in 0..4 {
        v.xdotool(&["key", "bracketright"]);
    }
    let line = v.wait_for("env_rotation_deg=60", 20);
    let rotated = v.shot(&d);
    let shading = rotated.shading_difference(&before);
    eprintln!("environment rotation 60°: shading {shading:.2}/255 ({line})");
    // The scene has an environment light, so the viewer must light the garment with it and
    // the rotation (through the eigenweightsets) must change the shading.
    assert!(line.contains("env_lighting=true"), "environment light not in use: {line}");
    assert!(shading > 1.0, "environment rotation changed the shading by {shading:.2}/255");

    let id: u32 = window.parse().expect("numeric window id");
    close_window(&v.display, id);
    let deadline = Instant::now() + Duration::from_secs(10);
    let status = loop {
        if let Some(s) = v.child.try_wait().unwrap() {
            break s;
        }
        assert!(Instant::now() < deadline, "the viewer did not exit within 10 s of the close");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "exit status {status:?}");
    eprintln!("{test}: {:.1} s", t0.elapsed().as_secs_f64());
}

/// Runs a headless `btf view`; `None` (skipped) without an adapter.
fn headless(d: &Dir, test: &str, args: &[&str]) -> Option<String> {
    let o = d.btf(args);
    let err = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() && err.contains("no GPU adapter") {
        skip(test, &err);
        return None;
    }
    assert!(o.status.success(), "btf {args:?}: {err}");
    Some(String::from_utf8(o.stdout).unwrap())
}

#[test]
fn turntable_writes_a_full_turn() {
    let d = Dir::new();
    let scene = garment_scene(&d);
    let s = scene.to_str().unwrap();
    let Some(_) = headless(&d, "turntable", &["view", s, "--turntable", "4", "-o", "tt"]) else {
        return;
    };
    let frames: Vec<Shot> =
        (0..4).map(|i| Shot::load(&d.path(&format!("tt/turntable-{i:04}.png")))).collect();
    for (i, f) in frames.iter().enumerate() {
        assert!(f.coverage() > 0.05, "frame {i} covers {:.3}", f.coverage());
    }
    // Every frame differs from the first; at 90° and 270° the silhouette does (at 180° the
    // back's outline is nearly the front's mirror image).
    for i in 1..4 {
        let (changed, xor) =
            (frames[i].changed(&frames[0], 8), frames[i].silhouette_xor(&frames[0]));
        eprintln!("turntable frame {i} vs 0: changed {changed:.3}, silhouette xor {xor:.3}");
        assert!(changed > 0.05, "frame {i} vs 0: changed {changed:.3}");
        assert!(i == 2 || xor > 0.03, "frame {i} vs 0: silhouette xor {xor:.3}");
    }
    // No temporary files are left; `--resume` redoes only the missing frame.
    let names: Vec<String> = std::fs::read_dir(d.path("tt"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != ".btf-output.json") // the marker that lets a rerun replace the folder
        .collect();
    assert_eq!(names.len(), 4, "{names:?}");
    let kept = std::fs::metadata(d.path("tt/turntable-0000.png")).unwrap().modified().unwrap();
    std::fs::remove_file(d.path("tt/turntable-0002.png")).unwrap();
    headless(&d, "turntable", &["view", s, "--turntable", "4", "-o", "tt", "--resume"]).unwrap();
    let again = Shot::load(&d.path("tt/turntable-0002.png"));
    assert_eq!(again.changed(&frames[2], 0), 0.0, "re-rendered frame is identical");
    let now = std::fs::metadata(d.path("tt/turntable-0000.png")).unwrap().modified().unwrap();
    assert_eq!(kept, now, "an existing frame was rewritten");
    // Without -o the export is refused with a message that says what is missing.
    let err = d.fails(&["view", s, "--turntable", "4"]);
    assert!(err.contains("-o DIR"), "{err}");
}

#[test]
fn bench_reports_latency_per_interaction() {
    let d = Dir::new();
    let scene = garment_scene(&d);
    let args = ["view", scene.to_str().unwrap(), "--bench", "2", "--env", "sky.exr"];
    let Some(out) = headless(&d, "bench", &args) else { return };
    let json = out.lines().last().unwrap();
    let rows: Vec<serde_json::Value> = serde_json::from_str(json).unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r["change"].as_str().unwrap()).collect();
    assert_eq!(names, ["camera move", "light move", "environment rotation", "environment swap"]);
    for r in &rows {
        let total = r["total_ms"].as_f64().unwrap();
        let sum = r["update_ms"].as_f64().unwrap() + r["render_ms"].as_f64().unwrap();
        assert!(total > 0.0 && (total - sum).abs() < 1e-2 + 1e-3 * total, "{r}");
    }
    // (With two samples the medians are means, so total = update + render exactly.)
    assert!((rows[0]["ratio_to_camera"].as_f64().unwrap() - 1.0).abs() < 1e-9);
}

/// The shirt in `m.eig` on the purple background at exposure 1.5, seen from `eye` (target
/// at chest height), with a point light at `light` and the lights in `more`.
fn shirt_scene(w: u32, h: u32, eye: [f32; 3], light: [f32; 3], power: f32, more: &str) -> String {
    format!(
        r#"
[output]
width = {w}
height = {h}
exposure = 1.5
background = [0.1, 0.0, 0.1]

[[meshes]]
path = "shirt.obj"

[[materials]]
store = "m.eig"
uv_scale = 6.0

[camera]
eye = {eye:?}
target = [0.0, 0.0, 0.36]
up = [0.0, 0.0, 1.0]
fov_y_deg = 38.0

[[lights]]
kind = "point"
position = {light:?}
intensity = [{power:?}, {power:?}, {power:?}]

{more}"#
    )
}

/// The scene of [`turntable_frames_are_btf_render_frames`] with the camera, the point light
/// and the environment turned by `deg` (0 or 90) about the vertical through the target.
fn turned_scene(deg: u32) -> String {
    let (eye, light, rotation) = match deg {
        0 => ([0.3, -1.5, 0.5], [-0.9, -1.6, 1.5], 240.0),
        // (x, y) − pivot turned by +90° about +z: (x, y) → (−y, x)
        90 => ([1.5, 0.3, 0.5], [1.6, -0.9, 1.5], 330.0),
        _ => unreachable!(),
    };
    let sky = format!(
        "[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nexposure = 0.014\n\
         rotation_deg = {rotation:?}\nvisibility_res = 8\ncache_dir = \"cache\"\n"
    );
    shirt_scene(96, 72, eye, light, 6.0, &sky)
}

/// Root-mean-square difference of two images over the root-mean-square of the first (8-bit
/// sRGB levels, every pixel).
fn rel_rmse(a: &Shot, b: &Shot) -> f64 {
    assert_eq!((a.w, a.h), (b.w, b.h));
    let (mut d2, mut a2) = (0.0, 0.0);
    for (x, y) in a.rgb.iter().zip(&b.rgb) {
        d2 += (*x as f64 - *y as f64).powi(2);
        a2 += (*x as f64).powi(2);
    }
    (d2 / a2.max(1.0)).sqrt()
}

/// Turntable frame `i` is `btf render` of the scene turned by `i · 360°/N`: the same camera,
/// lights and environment rotation give the same pixels. (Before, the turntable started the
/// environment at 0° instead of the scene's `rotation_deg`: a dimmer, greyer garment, rel.
/// RMSE 0.26 against `btf render`.) Exact gathers (no eigenweightsets): the viewer computes
/// every vertex side's visibility so that the camera can orbit, `btf render` only the sides
/// its camera sees, and an eigenweightset basis fitted over other sides approximates the
/// rotation differently (≈ 1 % here).
#[test]
fn turntable_frames_are_btf_render_frames() {
    let d = Dir::new();
    d.ok(&["synth", "material", "--kind", "corduroy", "--size", "8", "-o", "m.btf"]);
    d.ok(&["compress", "m.btf", "-c", "4", "-o", "m.eig"]);
    d.ok(&["synth", "mesh", "--kind", "shirt", "-o", "shirt.obj"]);
    d.ok(&["synth", "env", "--kind", "sky", "--width", "64", "-o", "sky.exr"]);
    for deg in [0, 90] {
        std::fs::write(d.path(&format!("s{deg}.toml")), turned_scene(deg)).unwrap();
    }
    let test = "turntable = render";
    let Some(_) = headless(&d, test, &["view", "s0.toml", "--turntable", "4", "-o", "tt"]) else {
        return;
    };
    for (frame, deg) in [(0, 0), (1, 90)] {
        let png = format!("r{deg}.png");
        d.ok(&["render", &format!("s{deg}.toml"), "-o", &png]);
        let rendered = Shot::load(&d.path(&png));
        let turned = Shot::load(&d.path(&format!("tt/turntable-{frame:04}.png")));
        let (e, cover) = (rel_rmse(&rendered, &turned), rendered.coverage());
        eprintln!("turntable frame {frame} vs btf render at {deg}°: rel. RMSE {e:.2e}");
        assert!(cover > 0.1, "the garment covers {cover:.3} of the frame");
        assert!(e <= 1e-3, "turntable frame {frame} vs btf render at {deg}°: rel. RMSE {e:.2e}");
    }
}

/// The pixels of window `id` on `display` (`xwd`, 32-bit ZPixmap as Xvfb's 24-bit screen
/// gives it), as an RGB [`Shot`] of the window's size.
fn capture_window(display: &str, id: &str) -> Shot {
    let o = Command::new("xwd")
        .args(["-id", id, "-silent"])
        .env("DISPLAY", display)
        .output()
        .expect("xwd runs");
    assert!(o.status.success(), "xwd: {}", String::from_utf8_lossy(&o.stderr));
    let b = o.stdout;
    let u32_at = |i: usize| u32::from_be_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
    let (header, format, w, h) = (u32_at(0) as usize, u32_at(2), u32_at(4), u32_at(5));
    let (byte_order, bpp, line) = (u32_at(7), u32_at(11), u32_at(12) as usize);
    let (masks, ncolors) = ([u32_at(14), u32_at(15), u32_at(16)], u32_at(19) as usize);
    assert_eq!((format, bpp), (2, 32), "xwd: not a 32-bit ZPixmap");
    let data = &b[header + 12 * ncolors..];
    let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
    for y in 0..h as usize {
        for x in 0..w as usize {
            let p: [u8; 4] = data[y * line + 4 * x..][..4].try_into().unwrap();
            let v = if byte_order == 0 { u32::from_le_bytes(p) } else { u32::from_be_bytes(p) };
            rgb.extend(masks.map(|m| ((v & m) >> m.trailing_zeros()) as u8));
        }
    }
    Shot { w: w as usize, h: h as usize, rgb }
}

/// `rect` (x, y, w, h in window pixels) cut out of `s`.
fn crop(s: &Shot, r: [usize; 4]) -> Shot {
    let mut rgb = Vec::with_capacity(r[2] * r[3] * 3);
    for y in r[1]..r[1] + r[3] {
        rgb.extend_from_slice(&s.rgb[3 * (y * s.w + r[0])..3 * (y * s.w + r[0] + r[2])]);
    }
    Shot { w: r[2], h: r[3], rgb }
}

/// What the window presents — the frame encoded on the GPU into the texture the present
/// pass samples (exposure and sRGB in `present.wgsl`), never read back — equals `btf render`
/// of the same scene at the frame area's size, within rel. RMSE 1e-3 of 8-bit levels.
#[test]
fn window_presents_what_btf_render_renders() {
    let test = "window_presents_what_btf_render_renders";
    for tool in ["Xvfb", "xdotool", "xwd"] {
        if !have(tool) {
            return skip(test, &format!("{tool} is not installed (apt-get install xvfb x11-apps)"));
        }
    }
    let d = Dir::new();
    d.ok(&["synth", "material", "--kind", "corduroy", "--size", "8", "-o", "m.btf"]);
    d.ok(&["compress", "m.btf", "-c", "4", "-o", "m.eig"]);
    d.ok(&["synth", "mesh", "--kind", "shirt", "-o", "shirt.obj"]);
    d.ok(&["synth", "env", "--kind", "sky", "--width", "64", "-o", "sky.exr"]);
    std::fs::write(d.path("s0.toml"), turned_scene(0)).unwrap();
    let x = Xvfb::start();
    let mut v = Viewer::spawn(&d, &x.display, &d.path("s0.toml"), &["--no-panel"]);
    let Some((window, _, r)) = settle(&v) else {
        let status = v.child.try_wait().unwrap();
        return skip(test, &format!("the viewer showed no frame (exit {status:?})"));
    };
    std::thread::sleep(Duration::from_millis(500)); // presented after the frame line
    let r: Vec<usize> = r.iter().map(|&t| t as usize).collect();
    let shown = crop(&capture_window(&v.display, &window), [r[0], r[1], r[2], r[3]]);
    let (w, h) = (r[2].to_string(), r[3].to_string());
    d.ok(&["render", "s0.toml", "--width", &w, "--height", &h, "-o", "r.png"]);
    let rendered = Shot::load(&d.path("r.png"));
    let e = rel_rmse(&rendered, &shown);
    eprintln!("{test}: {w}×{h} frame presented vs btf render: rel. RMSE {e:.2e}");
    assert!(rendered.coverage() > 0.1, "the garment covers {:.3}", rendered.coverage());
    assert!(e <= 1e-3, "presented frame vs btf render: rel. RMSE {e:.2e}");
    // Presenting reads nothing back: over five camera moves, the bytes mapped to the CPU grow
    // by the pass timestamps at most (a few hundred bytes a frame when the adapter has them),
    // not by a frame (w × h × 16 bytes).
    let before = read_back_bytes(&v.last_frame.borrow());
    let (cx, cy) = ((r[2] / 2).to_string(), (r[3] / 2).to_string());
    v.xdotool(&["mousemove", "--window", &window, &cx, &cy]);
    let mut after = before;
    for k in 1..=5 {
        let x = (r[2] / 2 + 10 * k).to_string();
        v.xdotool(&["mousedown", "1", "mousemove", "--window", &window, &x, &cy, "mouseup", "1"]);
        after = read_back_bytes(&v.wait_for("change=Camera", 20));
    }
    let frame_bytes = (r[2] * r[3] * 16) as u64;
    eprintln!("{test}: {} bytes read back over 5 presented frames", after - before);
    assert!(after - before < 5 * 4096, "read back {} bytes over 5 frames", after - before);
    assert!(after - before < frame_bytes / 10, "a frame is {frame_bytes} bytes");
    let _ = v.child.kill();
    let _ = v.child.wait();
}
