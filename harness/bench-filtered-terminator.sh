#!/usr/bin/env bash
# Terminator interplay of bump-map filtering (issue 12): the shipped
# cylinder-noise bumps baked into a height map over the cylinder's (u, v),
# rendered as bump with `none` and `estevez2019`, unfiltered and through a
# roughness filter at fixed pyramid levels (footprints of 2^L texels: the
# cylinder seen from farther away), each compared by `penumbra compare`
# with the displacement truth of the same map. Prints the terminator-region
# profile RMSE [95 % bootstrap interval] in % of albedo*E/pi, then the
# evaluator's throughput with the filter off and on.
#
#   bash harness/bench-filtered-terminator.sh [FILTER] [SIZE]
#     FILTER: a roughness filter id (default pixar2014)
#     SIZE:   texels around the cylinder (default 1024)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
penumbra="${PENUMBRA_BUILD_DIR:-$root/build}/penumbra"
filter="${1:-pixar2014}"
size="${2:-1024}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

scene="$root/scenes/cylinder-noise.json"
"$penumbra" bake "$scene" --on shape --size "$size" -o "$work/heights.exr" > /dev/null
map="{\"type\": \"height-map\", \"file\": \"$work/heights.exr\", \"amplitude\": 1"
common=(--set /camera/spp=64)

"$penumbra" render "$scene" -o "$work/truth.exr" "${common[@]}" --set "/height=$map}" \
  --set /representation=displacement > /dev/null

rmse() {  # reference test -> "value [low, high]" in % of albedo*E/pi
  "$penumbra" compare --json "$1" "$2" | python3 -c '
import json, sys
p = json.load(sys.stdin)["profile"]
v, lo, hi = p["rmse_terminator"], p["rmse_terminator_ci"][0], p["rmse_terminator_ci"][1]
print(f"{100 * v:.2f} [{100 * lo:.2f}, {100 * hi:.2f}]")'
}

printf '%-12s %-18s %s\n' method filter "terminator RMSE, % of albedo*E/pi [95 % CI]"
for method in none estevez2019; do
  "$penumbra" render "$scene" -o "$work/$method.exr" "${common[@]}" --set "/height=$map}" \
    --set "/terminator/method=$method" > /dev/null
  printf '%-12s %-18s %s\n' "$method" unfiltered "$(rmse "$work/truth.exr" "$work/$method.exr")"
  for level in 0 2 4 6; do
    "$penumbra" render "$scene" -o "$work/$method-$level.exr" "${common[@]}" \
      --set "/height=$map, \"filter\": {\"method\": \"$filter\", \"level\": $level}}" \
      --set "/terminator/method=$method" > /dev/null
    printf '%-12s %-18s %s\n' "$method" "$filter L$level" \
      "$(rmse "$work/truth.exr" "$work/$method-$level.exr")"
  done
done

echo
echo "throughput ($(nproc) cores, 512x512, 16 spp, estevez2019, GGX lobe weight 0.4):"
for f in none auto; do
  sets=(--set /camera/width=512 --set /camera/height=512 --set /camera/spp=16
        --set /terminator/method=estevez2019
        --set '/material={"albedo": 0.8, "specular": {"weight": 0.4, "roughness": 0.3}}')
  if [ "$f" = none ]; then
    sets+=(--set "/height=$map}")
  else
    sets+=(--set "/height=$map, \"filter\": {\"method\": \"$filter\"}}")
  fi
  line=$("$penumbra" render "$scene" -o "$work/speed-$f.exr" "${sets[@]}")
  echo "  filter $f: ${line#*: }"
done
