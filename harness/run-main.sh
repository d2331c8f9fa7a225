#!/usr/bin/env bash
# Quick start, first command: install what is missing, build, and render every
# example scene in scenes/ with the evaluator: raw bump, each terminator
# method and the displacement ground truth, into results/examples/
# (linear EXR with analysis channels, plus an sRGB PNG preview of each).
# The study issue turns this into the default study with its report.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/harness/setup.sh"
build="${PENUMBRA_BUILD_DIR:-$root/build}"
penumbra="$build/penumbra"
out="$root/results/examples"
mkdir -p "$out"
methods=$("$penumbra" methods --json | python3 -c 'import json,sys; print(" ".join(m["id"] for m in json.load(sys.stdin)))')
for scene in "$root"/scenes/*.json; do
  name="$(basename "$scene" .json)"
  "$penumbra" render "$scene" -q -o "$out/$name-displacement.exr" \
    --preview "$out/$name-displacement.png" --representation displacement
  "$penumbra" render "$scene" -q -o "$out/$name-smooth.exr" \
    --preview "$out/$name-smooth.png" --representation smooth
  for method in $methods; do
    "$penumbra" render "$scene" -q -o "$out/$name-bump-$method.exr" \
      --preview "$out/$name-bump-$method.png" --representation bump --method "$method"
  done
  echo "rendered $name: displacement, smooth and bump with: $methods"
done
echo "results: $out"
