#!/usr/bin/env bash
# Quick start, first command: install what is missing, build, and run the
# default study (scenes/studies/default.json: cylinder and sphere, grating and
# weave, three amplitudes, two light directions, every method, the evaluator,
# POV-Ray and Blender Cycles against displacement ground truth) into
# results/default/, then print the path of its report.html. A second run
# reuses the cached renders and takes well under a minute.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/harness/setup.sh"
build="${PENUMBRA_BUILD_DIR:-$root/build}"
"$build/penumbra" run "$root/scenes/studies/default.json" -o "$root/results/default" "$@"
