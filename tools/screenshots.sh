#!/usr/bin/env bash
# Regenerates the screenshots of docs/figures/ from the current build.
#
#   tools/screenshots.sh            # all screenshots
#   tools/screenshots.sh report     # only the ones named
#
# Needs: a release build (`cargo build --release`; CARGO_TARGET_DIR is honoured), a Vulkan
# adapter (lavapipe: `apt-get install mesa-vulkan-drivers`), headless Chromium
# (`apt-get install chromium`) for the report, and Xvfb, xwd and Pillow for the viewer
# (`apt-get install xvfb x11-apps`, `pip install pillow`). One function per screenshot, `shot_<name>`; add one and
# list it in ALL to extend the script.
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
FIGURES="$ROOT/docs/figures"
BTF="${BTF:-${CARGO_TARGET_DIR:-$ROOT/target}/release/btf}"   # or BTF=path/to/btf
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
ALL=(report viewer)

# Headless Chromium: `$1` (an HTML file) → `$2` (PNG) at 1280 × 800, the first screen.
chromium_shot() {
    local html="$1" png="$2"
    local browser
    browser="$(command -v chromium || command -v chromium-browser || command -v google-chrome)"
    "$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
        --user-data-dir="$WORK/chromium-profile" \
        --window-size=1280,800 --screenshot="$png.tmp.png" "file://$html" 2>/dev/null
    mv "$png.tmp.png" "$png"
    echo "wrote $png"
}

# The first screen of `btf demo`'s report (report.html), on the demo's defaults.
shot_report() {
    (cd "$WORK" && "$BTF" demo -o demo >/dev/null)
    chromium_shot "$WORK/demo/report.html" "$FIGURES/report-first-screen.png"
}

# The viewer at 1280 × 800 under Xvfb: the corduroy shirt of examples/scenes/shirt-env.toml
# under the sky, with the panel, once the frame has settled at the window's size; `xwd`
# dumps the screen and tools/xwd2png.py turns it into a PNG.
shot_viewer() {
    local out="$FIGURES/viewer-1280x800.png"
    command -v Xvfb >/dev/null && command -v xwd >/dev/null \
        || { echo "the viewer screenshot needs Xvfb and xwd: apt-get install xvfb x11-apps" >&2; return 1; }
    mkdir -p "$WORK/viewer"
    (
        cd "$WORK/viewer"
        cp "$ROOT/examples/scenes/shirt-env.toml" .
        "$BTF" synth material --kind corduroy --size 64 -o corduroy.btf >/dev/null
        "$BTF" compress corduroy.btf -o corduroy.eigen -c 16 >/dev/null
        "$BTF" synth mesh --kind shirt -o shirt.obj >/dev/null
        "$BTF" synth env --kind sky --width 512 -o sky.exr >/dev/null
        "$BTF" synth env --kind studio --width 256 -o studio.exr >/dev/null
        local n=99
        while [ -e "/tmp/.X11-unix/X$n" ] || [ -e "/tmp/.X$n-lock" ]; do n=$((n + 1)); done
        Xvfb ":$n" -screen 0 1280x800x24 -nolisten tcp >/dev/null 2>&1 &
        local xvfb=$!
        sleep 1
        # the frame area is the window less the panel (250 points)
        DISPLAY=":$n" "$BTF" view shirt-env.toml --env sky.exr --env studio.exr \
            --width 1030 --height 800 --log >viewer.log 2>&1 &
        local viewer=$!
        for _ in $(seq 1 240); do
            grep -q "^layout 250 0 1030 800" viewer.log && break
            sleep 0.5
        done
        sleep 2
        DISPLAY=":$n" xwd -root -silent >screen.xwd
        kill "$viewer" "$xvfb" 2>/dev/null || true
        wait "$viewer" "$xvfb" 2>/dev/null || true
        python3 "$ROOT/tools/xwd2png.py" screen.xwd "$out.tmp.png"
    )
    mv "$out.tmp.png" "$out"
    echo "wrote $out"
}

main() {
    [ -x "$BTF" ] || { echo "no release build at $BTF (cargo build --release)" >&2; exit 1; }
    mkdir -p "$FIGURES"
    local names=("$@")
    [ ${#names[@]} -gt 0 ] || names=("${ALL[@]}")
    for n in "${names[@]}"; do
        declare -F "shot_$n" >/dev/null || { echo "unknown screenshot '$n' (known: ${ALL[*]})" >&2; exit 2; }
        "shot_$n"
    done
}

main "$@"
