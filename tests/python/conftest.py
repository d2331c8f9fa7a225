"""Shared fixtures of the Python module's tests (CTest runs them as Python.*).

CTest sets PYTHONPATH to <build>/python and PENUMBRA_BINARY and
PENUMBRA_SOURCE_DIR, so that each test checks the module against the
command line of the same build.
"""

import os
import shutil
import subprocess

import numpy as np
import pytest

BINARY = os.environ.get("PENUMBRA_BINARY", "build/penumbra")
SOURCE = os.environ.get("PENUMBRA_SOURCE_DIR", os.getcwd())


def cli(*args, check=True):
    """The command line as a separate process: (exit status, stdout, stderr)."""
    p = subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True, timeout=600)
    if check and p.returncode != 0:
        raise AssertionError(f"penumbra {' '.join(map(str, args))} exited {p.returncode}: "
                             f"{p.stderr}")
    return p.returncode, p.stdout, p.stderr


def source(*parts):
    return os.path.join(SOURCE, *parts)


@pytest.fixture
def folder(request):
    """/tmp/penumbra-Python-<test>, emptied first (tests/temp_dir_test.h's convention)."""
    path = f"/tmp/penumbra-Python-{request.node.name}"
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    return path


def estevez2019_cosines(cos_light, cos_deviation):
    """Conty Estevez, Lecocq and Stein 2019 (Ray Tracing Gems ch. 12) in
    NumPy, on the two cosines it reads: alpha^2 = tan^2(delta) / 8 clamped
    to [0, 1], G = 2 / (1 + sqrt(1 + alpha^2 tan^2 theta_i)); |cos delta| and
    cos theta_i clamped below at 1e-6, as core/terminator.cpp does."""
    cos_d = np.minimum(np.abs(cos_deviation), 1.0)
    with np.errstate(divide="ignore"):
        alpha2 = np.clip(0.125 * (1.0 - cos_d * cos_d) / (cos_d * cos_d), 0.0, 1.0)
    cos_i = np.maximum(np.abs(cos_light), 1e-6)
    tan2_i = (1.0 - cos_i * cos_i) / (cos_i * cos_i)
    return np.clip(2.0 / (1.0 + np.sqrt(1.0 + alpha2 * tan2_i)), 0.0, 1.0)
