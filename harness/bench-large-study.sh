#!/usr/bin/env bash
# A study of about 10^5 renders, for the planning, cache and report
# benchmarks of a large sweep (README, "Speed"): evaluator only, 8x8 pixels
# at 1 sample so that rendering is cheap and the pipeline around it is what
# is measured. Prints wall time and peak memory of each step.
#   bash harness/bench-large-study.sh [OUT_DIR] [AMPLITUDES]
# AMPLITUDES (default 25) sets the size: 25 x 20 frequencies x 25 light
# directions = 12500 variants x 8 renders = 100000 renders.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-/tmp/penumbra-large}"
amplitudes="${2:-25}"
bin="${PENUMBRA:-$root/build/penumbra}"
mkdir -p "$out"
study="$out/large.json"
/usr/bin/python3 - "$root" "$amplitudes" > "$study" <<'PY'
import json, math, sys
root, n = sys.argv[1], int(sys.argv[2])
amplitudes = [round(0.002 + 0.001 * i, 6) for i in range(n)]
frequencies = [round(4.0 + 0.5 * i, 6) for i in range(20)]
# Light elevations from -10 to +14 degrees around the terminator.
lights = [[-1.0, 0.0, round(math.tan(math.radians(-10 + i)), 6)] for i in range(25)]
print(json.dumps({
    "version": 1, "name": "large",
    "scenes": [root + "/scenes/calibration/cylinder.json"],
    "set": {"/camera/width": 8, "/camera/height": 8, "/camera/spp": 1,
            "/displacement/edge_length": 0.05},
    "axes": [
        {"pointer": "/height/amplitude", "values": amplitudes},
        {"pointer": "/height/frequency", "values": frequencies},
        {"pointer": "/light/direction", "values": lights}],
    "methods": ["none", "chiang2019", "chiang2019-sine", "estevez2019",
                "estevez2019-reciprocal", "deshmukh2020",
                {"id": "shading-offset", "parameters": {"s": 0.3}}],
    "renderers": ["evaluator"],
    "ground_truth": {"max_edge_refinements": 0, "max_spp_refinements": 0},
    "plots": [{"metric": "profile.rmse_terminator", "x": "/height/amplitude",
               "y": "/height/frequency", "kind": "heatmap"}]}, indent=1))
PY
measure() {  # LABEL COMMAND...: runs it, prints wall seconds and peak RSS
  local label="$1"; shift
  /usr/bin/time -f "$label: %e s wall, %U s user, %M KiB peak RSS" "$@" > "$out/$label.log" 2> "$out/$label.time" \
    || { tail -5 "$out/$label.log" "$out/$label.time"; exit 1; }
  tail -1 "$out/$label.time"
}
echo "study $study ($(nproc) cores)"
measure plan-empty-cache "$bin" run "$study" -o "$out/run" --dry-run
head -3 "$out/plan-empty-cache.log"
measure render-and-report "$bin" run "$study" -o "$out/run" --no-figures -q
measure plan-full-cache "$bin" run "$study" -o "$out/run" --dry-run
measure report-from-cache "$bin" run "$study" -o "$out/run" --no-figures -q
measure figures-and-html "$bin" report "$out/run"
ls -l "$out/run/report.json" "$out/run/metrics.csv" "$out/run/report.html" 2>/dev/null | awk '{print $5, $9}'
