#!/usr/bin/env bash
# Regenerates the screenshots of docs/figures/ from the current build.
#
#   tools/screenshots.sh            # all screenshots
#   tools/screenshots.sh report     # only the ones named
#
# Needs: a release build (`cargo build --release`; CARGO_TARGET_DIR is honoured), a Vulkan
# adapter (lavapipe: `apt-get install mesa-vulkan-drivers`) and headless Chromium
# (`apt-get install chromium`). One function per screenshot, `shot_<name>`; add one and
# list it in ALL to extend the script.
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
FIGURES="$ROOT/docs/figures"
BTF="${BTF:-${CARGO_TARGET_DIR:-$ROOT/target}/release/btf}"   # or BTF=path/to/btf
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
ALL=(report)

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
