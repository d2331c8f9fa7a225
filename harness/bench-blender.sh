#!/usr/bin/env bash
# Benchmark: Blender renders of the default study's size (128x128, 32 spp,
# one thread each, as a 2-job study runs them) of the sphere grating, one
# process per render against one serving process (blender_render.py --serve).
# The serving process gets two jobs on one mesh in turn, as a study sends a
# variant's jobs: bump with methods none and chiang2019 (another material
# each time: the mesh is kept), and displacement under two light directions
# (the same material: mesh, material and Cycles' BVH are kept). Prints
# seconds per render and whether every served image has the bytes of its job
# rendered alone.
#
#   bash harness/bench-blender.sh [N]     # N renders of each kind (default 8)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
penumbra="${PENUMBRA_BUILD_DIR:-$root/build}/penumbra"
script="$root/harness/blender_render.py"
n="${1:-8}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
blender=(blender -b -t 1 --factory-startup -noaudio --python-exit-code 1 --python "$script" --)

export_job() {  # export_job NAME REPRESENTATION [--set ...]
  local name="$1" rep="$2"
  shift 2
  "$penumbra" export "$root/scenes/sphere-grating.json" --to blender -o "$work/$name" \
    --representation "$rep" --width 128 --height 128 --spp 32 \
    --set /displacement/edge_length=0.006 "$@" > /dev/null
}

for rep in bump displacement; do
  if [ "$rep" = bump ]; then
    export_job "$rep-0" bump
    export_job "$rep-1" bump --set /terminator/method=chiang2019
  else
    export_job "$rep-0" displacement
    export_job "$rep-1" displacement --set '/light/direction=[-1,0.2,0.3]'
  fi
  start=$(date +%s.%N)
  for i in $(seq "$n"); do
    k=$((i % 2))
    "${blender[@]}" "$work/$rep-$k/job.json" "$work/$rep-alone-$i.exr" --threads 1 > /dev/null 2>&1
  done
  alone=$(echo "($(date +%s.%N) - $start) / $n" | bc -l)
  start=$(date +%s.%N)
  for i in $(seq "$n"); do
    printf '{"job":"%s","output":"%s","threads":1}\n' "$work/$rep-$((i % 2))/job.json" \
      "$work/$rep-served-$i.exr"
  done | "${blender[@]}" --serve > "$work/$rep-served.log" 2>&1
  served=$(echo "($(date +%s.%N) - $start) / $n" | bc -l)
  same=yes
  for i in $(seq "$n"); do
    cmp -s "$work/$rep-alone-$i.exr" "$work/$rep-served-$i.exr" || same=no
  done
  kept=$(grep -c " kept, " "$work/$rep-served.log" || true)
  printf '%-12s one process per render %.2f s/render, one serving process %.2f s/render (%d renders, %d on a kept mesh; same bytes: %s)\n' \
    "$rep" "$alone" "$served" "$n" "$kept" "$same"
done
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
