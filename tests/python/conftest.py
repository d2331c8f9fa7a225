"""Shared fixtures of the Python module's tests (CTest runs them as Python.*).

CTest sets PYTHONPATH to <build>/python and PENUMBRA_BINARY and
PENUMBRA_SOURCE_DIR, so that each test checks the module against the
command line of the same build.
"""

import os
import shutil
import subprocess

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
