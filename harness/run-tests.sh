#!/usr/bin/env bash
# Quick start, second command: install what is missing, build with warnings
# as errors, run every test (GoogleTest through CTest).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/harness/setup.sh"
build="${PENUMBRA_BUILD_DIR:-$root/build}"
cd "$build"
ctest --output-on-failure --parallel "$(nproc)" --timeout 900
