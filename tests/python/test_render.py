"""pn.render, pn.load_scene and pn.compare against `penumbra render` and
`penumbra compare --json` run as separate processes."""

import json
import os
import re
import subprocess

import numpy as np
import pytest

import penumbra as pn
from conftest import cli, source

SCENE = source("scenes", "sphere-grating.json")
SMALL = ["--width", "40", "--height", "40", "--spp", "2"]


def assert_same_bits(a, b):
    # An EXR file lists its channels by name, not in the render's order.
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name].shape == b[name].shape, name
        # Bits, not values: NaN or -0 would hide behind ==.
        np.testing.assert_array_equal(a[name].view(np.uint32), b[name].view(np.uint32),
                                      err_msg=name)


def oiiotool_channels(exr):
    """The EXR's channels as OpenImageIO's oiiotool reads them: a reader that
    shares no code with Penumbra's, printing 9 decimals."""
    info = subprocess.run(["oiiotool", "--info", "-v", exr], capture_output=True, text=True,
                          check=True).stdout
    names = re.search(r"channel list: (.*)", info).group(1).split(", ")
    dump = subprocess.run(["oiiotool", "--dumpdata", exr], capture_output=True, text=True,
                          check=True).stdout
    rows = [[float(v) for v in line.split(":", 1)[1].split()]
            for line in dump.splitlines() if line.strip().startswith("Pixel (")]
    values = np.array(rows)
    return {name: values[:, k] for k, name in enumerate(names)}


@pytest.mark.parametrize("method", ["chiang2019", "estevez2019-reciprocal", "cycles45"])
def test_render_gives_the_cli_bits(method, folder):
    exr = os.path.join(folder, "cli.exr")
    cli("render", SCENE, "-o", exr, "--method", method, *SMALL, "--threads", "2", "-q")
    from_cli = pn.read_exr(exr)
    img = pn.render(SCENE, method=method, width=40, height=40, spp=2, threads=1)
    assert img.channels == ["R", "G", "B", "A", "analysis.theta", "analysis.deviation",
                            "analysis.G", "analysis.view"]
    assert_same_bits(img, from_cli)
    assert img.attributes == {k: v for k, v in from_cli.attributes.items()
                              if k.startswith("penumbra:")}
    assert img["R"].dtype == np.float32 and img["R"].shape == (40, 40)
    assert np.any(img["R"] > 0)
    # Each named array holds that channel, pixels row by row from the top:
    # within the 5e-10 that 9 printed decimals round to.
    for name, values in oiiotool_channels(exr).items():
        np.testing.assert_allclose(img[name].ravel(), values, rtol=0, atol=5.1e-10,
                                   err_msg=name)


def test_render_of_a_dict_with_set_equals_the_file(folder):
    scene = pn.load_scene(SCENE)
    scene["camera"]["width"] = 24
    scene["camera"]["height"] = 24
    scene["camera"]["spp"] = 1
    path = os.path.join(folder, "scene.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    exr = os.path.join(folder, "cli.exr")
    cli("render", path, "-o", exr, "--set", "/height/amplitude=0.02", "-q")
    img = pn.render(scene, set={"/height/amplitude": 0.02})
    assert_same_bits(img, pn.read_exr(exr))


def error_line(stderr):
    lines = [l for l in stderr.splitlines() if l.startswith("penumbra: error: ")]
    assert len(lines) == 1, stderr
    return lines[0][len("penumbra: error: "):]


@pytest.mark.parametrize("pointer,value", [("/camera/spp", 0), ("/terminator/method", "nope"),
                                           ("/height/amplitude", 5.0), ("/no_such_key", 1)])
def test_scene_error_is_the_cli_error(pointer, value, folder):
    scene = pn.load_scene(SCENE)
    path = os.path.join(folder, "bad.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    status, _, err = cli("render", path, "-o", os.path.join(folder, "x.exr"),
                         "--set", f"{pointer}={json.dumps(value)}", check=False)
    assert status == 2
    with pytest.raises(pn.SceneError) as e:
        pn.render(path, set={pointer: value})
    assert str(e.value) == error_line(err)
    assert e.value.file == path + " (after --set)"
    assert str(e.value).startswith(f"{e.value.file}: {e.value.pointer}: ")
    assert str(e.value).endswith(e.value.reason)
    assert e.value.pointer.startswith(pointer.rsplit("/", 1)[0])
    assert not os.path.exists(os.path.join(folder, "x.exr"))


def test_scene_error_of_a_file_that_is_not_json(folder):
    path = os.path.join(folder, "broken.json")
    with open(path, "w") as f:
        f.write("{\"version\": 1,")
    _, _, err = cli("render", path, "-o", os.path.join(folder, "x.exr"), check=False)
    with pytest.raises(pn.SceneError) as e:
        pn.load_scene(path)
    assert str(e.value) == error_line(err) and e.value.file == path


def test_compare_is_compare_json(folder):
    truth = os.path.join(folder, "truth.exr")
    bump = os.path.join(folder, "bump.exr")
    small = ["--width", "32", "--height", "32", "--spp", "2", "-q"]
    cli("render", SCENE, "-o", truth, "--representation", "displacement",
        "--set", "/displacement/edge_length=0.02", *small)
    cli("render", SCENE, "-o", bump, "--method", "chiang2019", *small)
    _, out, _ = cli("compare", truth, bump, "--json")
    expected = json.loads(out)
    assert pn.compare(truth, bump) == expected
    # Renders in memory go through their EXR attributes (the scene): same metrics.
    in_memory = pn.compare(pn.read_exr(truth),
                           pn.render(SCENE, method="chiang2019", width=32, height=32, spp=2))
    assert in_memory == dict(expected, reference=None, test=None)
    assert "rmse_terminator_ci" in expected["profile"]


def test_export_of_a_dict_writes_the_files_of_the_cli(folder):
    scene = pn.load_scene(SCENE)
    scene["height"]["amplitude"] = 0.015
    path = os.path.join(folder, "scene.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    cli("export", "--to", "povray", path, "-o", os.path.join(folder, "cli"))
    pn.export(scene, "povray", os.path.join(folder, "module"))
    names = sorted(os.listdir(os.path.join(folder, "cli")))
    assert names and names == sorted(os.listdir(os.path.join(folder, "module")))
    for name in names:
        with open(os.path.join(folder, "cli", name), "rb") as a, \
                open(os.path.join(folder, "module", name), "rb") as b:
            # The files name their scene and folder; all else is the same bytes.
            text_a = a.read().replace(path.encode(), b"SCENE").replace(b"/cli", b"/OUT")
            text_b = b.read().replace(os.path.join(os.getcwd(), "<dict>").encode(), b"SCENE")
            assert text_a == text_b.replace(b"/module", b"/OUT"), name
    with pytest.raises(RuntimeError, match='povray does not offer the method "estevez2019"'):
        pn.export(scene, "povray", os.path.join(folder, "bad"), method="estevez2019")
