#!/usr/bin/env bash
# Regenerates the README's picture docs/img/chatter-lobes.png: the `chatter --rrd` recording of
# the shipped pocket, rendered by Rerun's own viewer without a window (`rerun --headless
# --screenshot-to`), cropped to the 2D diagram.
# Needs: the Rerun CLI of .ci/run (target/rerun-venv), a Vulkan driver (Debian:
# `apt-get install mesa-vulkan-drivers`, a software renderer is enough) and Python's Pillow
# (`python3 -m venv /tmp/pil && /tmp/pil/bin/pip install pillow`, or PYTHON=... with Pillow).
set -euo pipefail
cd "$(dirname "$0")/.."
RERUN=${RERUN_BIN:-target/rerun-venv/bin/rerun}
PYTHON=${PYTHON:-/tmp/pil/bin/python}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo run --release --quiet -- chatter trajectories/pocket_chatter.ngc \
  --stock trajectories/pocket_chatter.stock.toml --rrd "$tmp/chatter.rrd" >/dev/null || true
test -s "$tmp/chatter.rrd"
XDG_RUNTIME_DIR=$tmp "$RERUN" --headless --renderer vulkan --window-size 1300x1000 \
  --screenshot-to "$tmp/shot.png" "$tmp/chatter.rrd" >/dev/null 2>&1
mkdir -p docs/img
"$PYTHON" - "$tmp/shot.png" docs/img/chatter-lobes.png <<'PY'
import sys
from PIL import Image
im = Image.open(sys.argv[1])
# The 2D view is the top-left panel: 71 % of the width, from under the menu bar to 56 % of the
# height (the layout of record::chatter's blueprint at 1300 × 1000 logical points).
w, h = im.size
crop = im.crop((0, round(0.031 * h), round(0.712 * w), round(0.566 * h)))
crop = crop.resize((1000, round(1000 * crop.size[1] / crop.size[0])), Image.LANCZOS)
crop.save(sys.argv[2], optimize=True)
PY
echo "wrote docs/img/chatter-lobes.png"
