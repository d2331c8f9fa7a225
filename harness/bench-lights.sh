#!/usr/bin/env bash
# Benchmark: the evaluator's camera samples per second under each light type
# against the sun, in one run: the sphere weave (A = 0.01) bumped with
# estevez2019 and its displaced truth, 256x256 at 64 spp on all cores, each
# light type rendered N times in turn (sun, sphere, quad, environment) and
# the median wall time kept. An area light's sample is drawn per camera
# sample (docs/evaluator.md#area-and-environment-lights); the sun's path is
# the one the studies take (SIMD packets for bump, Embree for the truth).
#
#   bash harness/bench-lights.sh [N]     # N renders of each (default 5)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
penumbra="${PENUMBRA_BUILD_DIR:-$root/build}/penumbra"
n="${1:-5}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
declare -A light=(
  [sun]='{"type": "distant", "direction": [-1, 0, -0.2], "irradiance": 3.141592653589793}'
  [sphere]='{"type": "sphere", "position": [-3, 0, -0.6], "radius": 0.5, "power": 400}'
  [quad]='{"type": "quad", "corner": [-3, -1, -1.5], "edge_u": [0, 2, 0], "edge_v": [0.3, 0, 1.5], "radiance": 3}'
  [environment]='{"type": "environment", "map": "blender:studiolights/world/forest.exr"}'
)
samples=$((256 * 256 * 64))
echo "penumbra render, 256x256, 64 spp ($samples camera samples), $(nproc) cores; $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //')"
printf '%-14s %-12s %12s %16s %10s\n' representation light "median s" "samples/s" "vs sun"
for rep in bump displacement; do
  sun=""
  for name in sun sphere quad environment; do
    times=()
    for i in $(seq "$n"); do
      start=$(date +%s.%N)
      "$penumbra" render "$root/scenes/sphere-weave.json" -o "$work/out.exr" -q \
        --representation "$rep" --method estevez2019 --width 256 --height 256 --spp 64 \
        --set "/light=${light[$name]}" --set /displacement/edge_length=0.006
      times+=("$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')")
    done
    median=$(printf '%s\n' "${times[@]}" | sort -g | sed -n "$(((n + 1) / 2))p")
    [ -z "$sun" ] && sun="$median"
    awk -v r="$rep" -v l="$name" -v t="$median" -v s="$sun" -v n="$samples" \
      'BEGIN { printf "%-14s %-12s %12.3f %16.0f %9.2fx\n", r, l, t, n / t, t / s }'
  done
done
