#!/usr/bin/env bash
# Benchmark: Blender renders of the default study's size (128x128, 32 spp,
# one thread each, as a 2-job study runs them), one process per render
# against one serving process (blender_render.py --serve), for a bump and a
# displacement job of the sphere grating. Prints seconds per render.
#
#   bash harness/bench-blender.sh [N]     # N renders of each kind (default 8)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
penumbra="${PENUMBRA_BUILD_DIR:-$root/build}/penumbra"
script="$root/harness/blender_render.py"
n="${1:-8}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
blender=(blender -b --factory-startup -noaudio --python-exit-code 1 --python "$script" --)

for rep in bump displacement; do
  "$penumbra" export "$root/scenes/sphere-grating.json" --to blender -o "$work/$rep" \
    --representation "$rep" --width 128 --height 128 --spp 32 \
    --set /displacement/edge_length=0.006 > /dev/null
  start=$(date +%s.%N)
  for i in $(seq "$n"); do
    "${blender[@]}" "$work/$rep/job.json" "$work/$rep-alone-$i.exr" --threads 1 > /dev/null 2>&1
  done
  alone=$(echo "($(date +%s.%N) - $start) / $n" | bc -l)
  start=$(date +%s.%N)
  for i in $(seq "$n"); do
    printf '{"job":"%s","output":"%s","threads":1}\n' "$work/$rep/job.json" "$work/$rep-served-$i.exr"
  done | "${blender[@]}" --serve > /dev/null 2>&1
  served=$(echo "($(date +%s.%N) - $start) / $n" | bc -l)
  same=yes
  for i in $(seq "$n"); do cmp -s "$work/$rep-alone-1.exr" "$work/$rep-served-$i.exr" || same=no; done
  printf '%-12s one process per render %.2f s/render, one serving process %.2f s/render (%d renders; same bytes: %s)\n' \
    "$rep" "$alone" "$served" "$n" "$same"
done
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
