#!/usr/bin/env python3
"""Penumbra's SSIM against an independent implementation, scikit-image's.

Renders pairs of Penumbra images that differ in method, light or shape,
runs `penumbra compare --no-mask --json` on each pair and checks its SSIM
against skimage.metrics.structural_similarity with the definition Penumbra
documents (analysis/metrics.h, ssim_unmasked): luminance (R+G+B)/3 of the
linear radiance, 11x11 Gaussian window of sigma 1.5 (skimage: truncate 3.5
gives the same radius 5), K1 = 0.01, K2 = 0.03, population (not sample)
covariances, dynamic range L = the reference's largest luminance, and the
mean over the pixels whose window lies inside the image (skimage crops the
same border). The images reach Python through oiiotool (OpenImageIO), not
through Penumbra's OpenEXR reader, as uncompressed 32-bit float TIFF.

Penumbra's default, masked SSIM (windows renormalised over the pixels both
renders fully cover) has no skimage counterpart; the unmasked one shares
its window, constants and luminance, so agreement here checks those.

Exit 77 (a skip for CTest) only when scikit-image is missing.
Usage: test_ssim_skimage.py PENUMBRA_BINARY SOURCE_DIR
"""

import json
import os
import struct
import subprocess
import sys
import tempfile

try:
    import numpy as np
    from skimage.metrics import structural_similarity
except ImportError as e:  # python3-skimage (harness/debian-packages.txt)
    print(f"SKIP: {e}")
    sys.exit(77)

PENUMBRA, SOURCE = sys.argv[1], sys.argv[2]
SCENES = os.path.join(SOURCE, "scenes")

# Both sides compute in double from the same float32 luminance; they differ
# only in summation order (skimage filters separably with scipy, Penumbra
# sums the 2-D window) and in the E[x^2] - E[x]^2 cancellation, each a few
# 1e-16 of L^2 against C2 = (0.03 L)^2 ~ 1e-3 L^2, so about 1e-12 in SSIM.
# 1e-9 leaves room for that (measured: under 2e-15) yet fails a change of
# window, constant, dynamic range, covariance normalisation or luminance
# (sample covariances alone move the method pairs by about 4e-5).
TOLERANCE = 1e-9


def render(scene, out, *extra):
    subprocess.run([PENUMBRA, "render", os.path.join(SCENES, scene), "-o", out, "--width", "96",
                    "--height", "80", "--spp", "4", "--quiet", *extra], check=True)


def read_float_tiff(path):
    """An uncompressed, interleaved 32-bit float TIFF as an array (rows, columns, samples)."""
    data = open(path, "rb").read()
    order = {b"II": "<", b"MM": ">"}[data[:2]]
    (ifd,) = struct.unpack(order + "I", data[4:8])
    (count,) = struct.unpack(order + "H", data[ifd:ifd + 2])
    tags = {}
    for i in range(count):
        entry = data[ifd + 2 + 12 * i:ifd + 14 + 12 * i]
        tag, kind, n, value = struct.unpack(order + "HHI4s", entry)
        if kind not in (3, 4):  # SHORT, LONG: all the tags read below
            continue
        size = (2 if kind == 3 else 4) * n
        raw = value if size <= 4 else data[struct.unpack(order + "I", value)[0]:][:size]
        tags[tag] = struct.unpack(order + ("H" if kind == 3 else "I") * n, raw[:size])
    # no compression, interleaved samples, IEEE floats, top row first
    for tag, expected in ((259, 1), (284, 1), (339, 3), (274, 1)):
        assert tags.get(tag, (1,))[0] == expected, (path, tag, tags.get(tag))
    assert set(tags[258]) == {32}, (path, tags[258])
    width, height, samples = tags[256][0], tags[257][0], tags[277][0]
    strips = b"".join(data[o:o + n] for o, n in zip(tags[273], tags[279]))
    pixels = np.frombuffer(strips, dtype=order + "f4", count=width * height * samples)
    return pixels.reshape(height, width, samples)


def luminance(exr, folder):
    """(R+G+B)/3 in float32, as Penumbra forms it."""
    tiff = os.path.join(folder, os.path.basename(exr) + ".tif")
    subprocess.run(["oiiotool", exr, "--ch", "R,G,B", "-d", "float", "--compression", "none",
                    "-o", tiff], check=True)
    rgb = read_float_tiff(tiff).astype(np.float32)
    return ((rgb[..., 0] + rgb[..., 1]) + rgb[..., 2]) / np.float32(3)


def main():
    with tempfile.TemporaryDirectory(prefix="penumbra-ssim-") as d:
        images = {
            "sphere-none": ("sphere-grating.json",),
            "sphere-chiang": ("sphere-grating.json", "--method", "chiang2019"),
            "sphere-smooth": ("sphere-grating.json", "--representation", "smooth"),
            "sphere-light": ("sphere-grating.json", "--set", "/light/direction=[-1,0.3,-0.6]"),
            "cylinder-none": ("cylinder-grating.json",),
            "cylinder-estevez": ("cylinder-grating.json", "--method", "estevez2019"),
        }
        for name, args in images.items():
            render(args[0], os.path.join(d, name + ".exr"), *args[1:])
        pairs = [("sphere-none", "sphere-none"), ("sphere-none", "sphere-chiang"),
                 ("sphere-chiang", "sphere-smooth"), ("sphere-none", "sphere-light"),
                 ("cylinder-none", "cylinder-estevez"), ("cylinder-estevez", "sphere-none")]
        failures, values = [], []
        for ref, test in pairs:
            ref_exr, test_exr = (os.path.join(d, n + ".exr") for n in (ref, test))
            result = subprocess.run([PENUMBRA, "compare", ref_exr, test_exr, "--no-mask", "--json"],
                                    capture_output=True, text=True)
            if result.returncode != 0:
                failures.append(f"{ref} vs {test}: exit {result.returncode}: {result.stderr}")
                continue
            image = json.loads(result.stdout)["image"]
            a, b = luminance(ref_exr, d), luminance(test_exr, d)
            data_range = float(a.astype(np.float64).max())
            expected = structural_similarity(
                b.astype(np.float64), a.astype(np.float64), data_range=data_range,
                gaussian_weights=True, sigma=1.5, use_sample_covariance=False, K1=0.01, K2=0.03)
            values.append(expected)
            print(f"{ref} vs {test}: penumbra {image['ssim']:.12f} skimage {expected:.12f} "
                  f"difference {image['ssim'] - expected:+.3e}")
            if abs(image["peak"] - data_range) > 1e-6 * data_range:
                failures.append(f"{ref} vs {test}: L {image['peak']} != {data_range}")
            if not abs(image["ssim"] - expected) <= TOLERANCE:
                failures.append(f"{ref} vs {test}: SSIM {image['ssim']} != skimage {expected}")
        # The pairs must span a range, or agreement would say little.
        if values and not (max(values) > 1 - 1e-12 and min(values) < 0.9):
            failures.append(f"SSIM values {values} do not span identical to dissimilar")
        for f in failures:
            print(f"FAIL: {f}")
        sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
