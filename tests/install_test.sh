#!/usr/bin/env bash
# cmake --install into a fresh prefix, then run the installed binary from
# another folder: it must find its scripts and scenes under PREFIX/share.
set -euo pipefail
build="$1"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
cd "$tmp"
bin="$tmp/prefix/bin/penumbra"
# The calibration scenes default to the installed copy.
"$bin" calibrate --help | grep -q -- "--scenes TEXT=$tmp/prefix/share/penumbra/scenes/calibration"
# The export names the installed Blender script.
"$bin" export --to blender "$tmp/prefix/share/penumbra/scenes/calibration/sphere.json" -o job \
  | grep -q -- "--python $tmp/prefix/share/penumbra/harness/blender_render.py"
# The report script runs from the installed copy (contour: matplotlib and Jinja2 imports).
"$bin" contour --method none --method chiang2019 --step 5 -o contour > /dev/null
test -s contour/contour.json
ls contour | grep -q '\.png$'
# PNG goes through the OpenImageIO module, loaded from PREFIX/lib/penumbra.
"$bin" render "$tmp/prefix/share/penumbra/scenes/calibration/sphere.json" --width 8 --height 8 \
  --spp 1 -q -o "$tmp/a.exr" --preview "$tmp/a.png"
test -s "$tmp/a.png"
echo "install test: ok ($tmp/prefix)"
