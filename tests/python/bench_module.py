"""The module's costs, measured in one run on this machine (docs/python.md).

  PYTHONPATH=build/python /usr/bin/python3 tests/python/bench_module.py [--threads 2]

1. pn.render against `penumbra render` of the same scene (the binary in
   the build folder), best of 3 each, the image's bits checked equal.
2. The estevez2019 factor per sample: the built-in through pn.factor
   against the same formula written in NumPy (tests/python/test_factor.py),
   on 10^6 random lit directions.
3. A user method (penumbra.method) that reimplements estevez2019 in NumPy
   against the built-in, rendering the bump cylinder (512^2, 64 spp by
   default: --user-width, --user-spp), best of 3 each, the images checked
   equal; the issue's target is at most 3x the built-in's time.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import penumbra as pn
from conftest import estevez2019_cosines
from penumbra import _build

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "cylinder-grating.json")


def best(f, repeat=3):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return min(times)


def estevez2019_numpy(ng, ns, wi):
    return estevez2019_cosines(np.einsum("ij,ij->i", ng, wi), np.einsum("ij,ij->i", ng, ns))


@pn.method("bench-estevez2019")
def estevez2019_user(cos_light, cos_deviation, cos_shading, cos_view):
    return estevez2019_cosines(cos_light, cos_deviation)


def user_method_ratio(width, spp, threads):
    def render(method):
        return pn.render(SCENE, method=method, width=width, height=width, spp=spp,
                         threads=threads)
    builtin = best(lambda: render("estevez2019"))
    user = best(lambda: render("bench-estevez2019"))
    a, b = render("estevez2019"), render("bench-estevez2019")
    ulps = max(int(np.max(np.abs(a[c].view(np.int32).astype(np.int64) -
                                 b[c].view(np.int32).astype(np.int64)))) for c in a)
    samples = width * width * spp
    print(f"user method (estevez2019 in NumPy) against the built-in, bump cylinder {width}x{width} "
          f"{spp} spp, {threads} threads: built-in {builtin:.3f} s "
          f"({builtin / samples * 1e9:.1f} ns/sample), user {user:.3f} s "
          f"({user / samples * 1e9:.1f} ns/sample), ratio {user / builtin:.2f} (target <= 3), "
          f"largest difference {ulps} float ulp")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--width", type=int, default=256)
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--user-width", type=int, default=512)
    parser.add_argument("--user-spp", type=int, default=64)
    a = parser.parse_args()
    binary = os.path.join(_build.BINARY_DIR, "penumbra")
    with tempfile.TemporaryDirectory() as folder:
        exr = os.path.join(folder, "cli.exr")
        args = [binary, "--threads", str(a.threads), "render", SCENE, "-o", exr, "-q",
                "--method", "estevez2019", "--width", str(a.width), "--height", str(a.width),
                "--spp", str(a.spp)]
        cli = best(lambda: subprocess.run(args, check=True))
        module = best(lambda: pn.render(SCENE, method="estevez2019", width=a.width,
                                        height=a.width, spp=a.spp, threads=a.threads))
        same = all(np.array_equal(pn.read_exr(exr)[c].view(np.uint32),
                                  pn.render(SCENE, method="estevez2019", width=a.width,
                                            height=a.width, spp=a.spp)[c].view(np.uint32))
                   for c in pn.read_exr(exr))
    print(f"render {a.width}x{a.width} {a.spp} spp, {a.threads} threads: CLI {cli:.3f} s "
          f"(process included), pn.render {module:.3f} s, ratio {module / cli:.3f}, "
          f"same bits {same}")

    rng = np.random.default_rng(1)
    n = 1_000_000
    ng = np.tile([0.0, 0.0, 1.0], (n, 1))
    ns = rng.normal(size=(n, 3)) * [0.3, 0.3, 0.0] + ng
    ns /= np.linalg.norm(ns, axis=1, keepdims=True)
    wi = rng.normal(size=(n, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wi[:, 2] = np.abs(wi[:, 2])
    builtin = best(lambda: pn.factor("estevez2019", ng, ns, wi))
    numpy = best(lambda: estevez2019_numpy(ng, ns, wi))
    diff = np.max(np.abs(pn.factor("estevez2019", ng, ns, wi) - estevez2019_numpy(ng, ns, wi)))
    print(f"estevez2019 factor, {n} samples: built-in {builtin / n * 1e9:.1f} ns/sample, "
          f"NumPy {numpy / n * 1e9:.1f} ns/sample, ratio {numpy / builtin:.2f}, "
          f"max |difference| {diff:.2e}")
    user_method_ratio(a.user_width, a.user_spp, a.threads)
    return 0


if __name__ == "__main__":
    sys.exit(main())
