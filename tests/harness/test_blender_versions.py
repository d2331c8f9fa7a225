#!/usr/bin/python3
"""harness/blender_render.py accepts the Blender versions it states and
refuses any other with one line on stderr and exit status 1.

Blender itself cannot be made to report another version, so a stand-in
`bpy` (and `mathutils`) on PYTHONPATH plays Blender: the script runs under
plain Python up to its version check, and for a supported version on to an
empty --serve session.  The pure check is also called directly.

Usage: test_blender_versions.py SOURCE_DIR
"""
import importlib.util
import os
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True  # leave no .pyc of the script in harness/

FAKE_BPY = """
class app:
    version = {version!r}
    version_string = {string!r}
"""
FAKE_MATHUTILS = "class Matrix: pass\nclass Vector: pass\n"


def write_fakes(folder, version):
    string = ".".join(map(str, version))
    with open(os.path.join(folder, "bpy.py"), "w") as f:
        f.write(FAKE_BPY.format(version=version, string=string))
    with open(os.path.join(folder, "mathutils.py"), "w") as f:
        f.write(FAKE_MATHUTILS)


def load_module(script, fakes):
    sys.path.insert(0, fakes)
    try:
        spec = importlib.util.spec_from_file_location("blender_render", script)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(fakes)


def main():
    script = os.path.join(sys.argv[1], "harness", "blender_render.py")
    failures = []

    def expect(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    with tempfile.TemporaryDirectory() as tmp:
        write_fakes(tmp, (3, 4, 1))
        m = load_module(script, tmp)
        first, last = m.BLENDER_SUPPORTED
        expect((first, last) == ((3, 4), (4, 4)),
               f"stated range 3.4 to 4.4 (got {first} to {last})")
        for v in [(3, 4, 0), (3, 4, 1), (3, 6, 5), (4, 0, 2), (4, 1, 0),
                  (4, 4, 3)]:
            expect(m.blender_version_problem(v) is None, f"{v} accepted")
        for v in [(2, 93, 18), (3, 3, 21), (4, 5, 0), (4, 5, 3), (5, 0, 0)]:
            p = m.blender_version_problem(v)
            expect(isinstance(p, str) and "\n" not in p
                   and p.startswith("Blender " + ".".join(map(str, v)) + " ")
                   and "3.4 to 4.4" in p, f"{v} refused: {p}")

        def run(version):
            write_fakes(tmp, version)
            env = dict(os.environ, PYTHONPATH=tmp)
            return subprocess.run(
                [sys.executable, script, "--", "--serve"], env=env,
                stdin=subprocess.DEVNULL, capture_output=True, text=True,
                timeout=60)

        for version in [(4, 5, 0), (3, 3, 0)]:
            r = run(version)
            lines = r.stderr.splitlines()
            expect(r.returncode == 1 and len(lines) == 1
                   and lines[0].startswith("blender_render.py: Blender ")
                   and "not supported" in lines[0] and r.stdout == "",
                   f"script under {version}: exit {r.returncode}, "
                   f"stderr {r.stderr!r}, stdout {r.stdout!r}")
        r = run((3, 4, 1))
        expect(r.returncode == 0 and r.stderr == ""
               and "serving (Blender 3.4.1)" in r.stdout,
               f"script under 3.4.1 serves: exit {r.returncode}, "
               f"stderr {r.stderr!r}")
    if failures:
        print(f"{len(failures)} failed")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
