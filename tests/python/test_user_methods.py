"""User methods (penumbra.method): a Python function measured as a built-in
method is. The reference is the built-in estevez2019 (Conty Estevez, Lecocq
and Stein 2019, Ray Tracing Gems ch. 12), reimplemented in NumPy from the
paper's formulas (conftest.estevez2019_cosines).

The images are compared to the bit (a float's last place, 1 ulp, where the
sums' order of operations differs: the evaluator adds a user method's
light as rest + sum(g * light), a built-in's as sum(value)); every case
below agrees exactly today."""

import json
import os
import runpy
import subprocess

import numpy as np
import pytest

import penumbra as pn
from conftest import BINARY, source

SCENES = source("scenes")
# A file of user methods, as a user writes one.
METHODS_FILE = f'''import sys
import penumbra as pn
sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r})
from conftest import estevez2019_cosines


@pn.method("user-estevez")
def user_estevez(cos_light, cos_deviation, cos_shading, cos_view):
    return estevez2019_cosines(cos_light, cos_deviation)
'''

# The same function, registered in this process under another id.
namespace = {}
exec(compile(METHODS_FILE.replace('"user-estevez"', '"estevez-numpy"'), "<methods>", "exec"),
     namespace)


@pn.method("half", parameters={"k": (0.5, "dimensionless, [0, 1]")})
def half(cos_light, cos_deviation, cos_shading, cos_view, k):
    return np.full_like(cos_light, k)


def ulps(a, b):
    return int(np.max(np.abs(a.view(np.int32).astype(np.int64) -
                             b.view(np.int32).astype(np.int64))))


@pytest.mark.parametrize("scene, sets", [
    ("cylinder-grating.json", {}),
    # A glossy lobe: G on every lobe, then on the diffuse one only (the
    # light no factor scales is added apart).
    ("sphere-weave.json", {"/material/specular": {"weight": 0.5, "roughness": 0.3},
                           "/terminator/lobes": "all"}),
    ("sphere-weave.json", {"/material/specular": {"weight": 0.5, "roughness": 0.3}}),
    # Area and environment lights: one light sample per camera sample.
    ("cylinder-noise.json", {"/light": {"type": "sphere", "position": [-3, 0, -1],
                                        "radius": 0.5, "power": 100}}),
    # The scalar path (a tessellated shape has no SIMD packets).
    ("sphere-grating.json", {"/shape/tessellation": {"segments": 24}}),
])
def test_a_numpy_estevez2019_renders_the_built_ins_pixels(scene, sets):
    args = dict(width=48, height=48, spp=8, set=sets)
    built_in = pn.render(os.path.join(SCENES, scene), method="estevez2019", **args)
    user = pn.render(os.path.join(SCENES, scene), method="estevez-numpy", **args)
    assert sorted(built_in) == sorted(user)
    for channel in built_in:
        assert ulps(built_in[channel], user[channel]) <= 1, channel
    assert float(np.max(built_in["R"])) > 0.0
    # Some samples have G < 1, so the factor did act.
    assert float(np.min(user["analysis.G"][user["A"] > 0])) < 0.99


def test_pn_factor_of_a_user_method_is_its_function_on_the_evaluators_cosines():
    rng = np.random.default_rng(3)
    n = 2000
    ng = np.tile([0.0, 0.0, 1.0], (n, 1))
    ns = rng.normal(size=(n, 3)) * [0.4, 0.4, 0.0] + ng
    ns /= np.linalg.norm(ns, axis=1, keepdims=True)
    wi = rng.normal(size=(n, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    np.testing.assert_allclose(pn.factor("estevez-numpy", ng, ns, wi),
                               pn.factor("estevez2019", ng, ns, wi), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(pn.factor(half, ng, ns, wi, k=0.3), np.full(n, 0.3))


def test_a_constant_factor_scales_raw_bump_and_fills_analysis_g():
    scene = os.path.join(SCENES, "cylinder-grating.json")
    raw = pn.render(scene, method="none", width=64, height=64, spp=4)
    for k in (0.5, 0.25):
        img = pn.render(scene, method=half, width=64, height=64, spp=4,
                        set={"/terminator/parameters/k": k})
        # k is a power of two: k * radiance is exact in float and double.
        np.testing.assert_array_equal(img["R"], np.float32(k) * raw["R"])
        hit = raw["A"] > 0
        np.testing.assert_array_equal(img["analysis.G"][hit], np.float32(k))
        for channel in ("A", "analysis.theta", "analysis.deviation", "analysis.view"):
            np.testing.assert_array_equal(img[channel], raw[channel])


def test_a_parameter_outside_its_domain_is_a_scene_error():
    with pytest.raises(pn.SceneError) as e:
        pn.render(os.path.join(SCENES, "cylinder-grating.json"), method="half", width=8,
                  height=8, spp=1, set={"/terminator/parameters/k": 2})
    assert e.value.pointer == "/terminator/parameters/k"
    assert "in [0, 1]" in e.value.reason


def test_an_unregistered_id_and_the_python_row_are_scene_errors():
    scene = os.path.join(SCENES, "cylinder-grating.json")
    for method, words in (("no-such-method", "unknown method"), ("python", "stands for")):
        with pytest.raises(pn.SceneError) as e:
            pn.render(scene, method=method, width=8, height=8, spp=1)
        assert e.value.pointer == "/terminator/method" and words in e.value.reason


def test_a_built_in_id_cannot_be_taken():
    with pytest.raises(ValueError, match="built-in"):
        pn.method("estevez2019")(half)


def raises(c_l, c_d, c_s, c_v):
    raise ValueError("no idea")


def nan_at_5(c_l, c_d, c_s, c_v):
    g = np.ones_like(c_l)
    g[5] = np.nan
    return g


def two_columns(c_l, c_d, c_s, c_v):
    return np.ones((len(c_l), 2))


def above_one(c_l, c_d, c_s, c_v):
    return np.full_like(c_l, 1.5)


@pytest.mark.parametrize("function, words", [
    (raises, "raised ValueError: no idea"),
    (nan_at_5, "returned nan at sample 5"),
    (two_columns, "returned an array of shape (42, 2) for a batch of 42 samples"),
    (above_one, "returned 1.5 at sample 0"),
])
def test_a_failing_function_fails_the_render_naming_the_method(function, words):
    pn.method("failing")(function)
    with pytest.raises(pn.UserMethodError) as e:
        pn.render(os.path.join(SCENES, "cylinder-grating.json"), method="failing", width=8,
                  height=8, spp=1)
    assert 'user method "failing"' in str(e.value) and words in str(e.value), str(e.value)


@pytest.fixture
def study(folder):
    path = os.path.join(folder, "study.json")
    with open(path, "w") as f:
        json.dump({
            "version": 1,
            "name": "python-user-methods",
            "scenes": [source("scenes", "calibration", "cylinder.json")],
            "set": {"/camera/width": 24, "/camera/height": 24, "/camera/spp": 2,
                    "/displacement/edge_length": 0.02},
            "axes": [{"pointer": "/height/amplitude", "label": "amplitude A (scene units)",
                      "values": [0.01, 0.02]}],
            "methods": ["none", "estevez2019"],
            "renderers": ["evaluator"],
        }, f)
    with open(os.path.join(folder, "methods.py"), "w") as f:
        f.write(METHODS_FILE)
    return folder


def rendered_now(stdout):
    line = next(x for x in stdout.splitlines() if x.startswith("study "))
    return int(line.split(" rendered now")[0].rsplit("(", 1)[1])


def metric_rows(out):
    import csv
    with open(os.path.join(out, "metrics.csv")) as f:
        return list(csv.DictReader(f))


def test_a_study_measures_a_user_method_like_the_built_in(study):
    out = os.path.join(study, "out")
    methods = os.path.join(study, "methods.py")
    # The binary hands --methods-from over to python3 -m penumbra.
    p = subprocess.run([BINARY, "run", os.path.join(study, "study.json"), "-o", out,
                        "--methods-from", methods, "--no-figures", "--no-fit", "-q"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr + p.stdout
    rows = metric_rows(out)
    by = {(r["variant"], r["method"]): r for r in rows if r["representation"] == "bump"}
    user = [k for k in by if k[1] == "user-estevez"]
    assert len(user) == 2
    skip = {"method", "method_label", "exr"}
    for variant, _ in user:
        a, b = by[(variant, "estevez2019")], by[(variant, "user-estevez")]
        differ = {k for k in a if k not in skip and a[k] != b[k]}
        assert not differ, differ

    # The same file in this process: the same digest, so nothing renders.
    runpy.run_path(methods)
    assert rendered_now(pn.run(os.path.join(study, "study.json"), out, "--no-figures",
                               "--no-fit", "-q", extra_methods=["user-estevez"])) == 0
    # An edited file renders the user method's two renders again, nothing else.
    with open(methods, "a") as f:
        f.write("# edited\n")
    runpy.run_path(methods)
    assert rendered_now(pn.run(os.path.join(study, "study.json"), out, "--no-figures",
                               "--no-fit", "-q", extra_methods=["user-estevez"])) == 2


def test_a_failing_user_method_fails_its_renders_and_caches_nothing(study):
    out = os.path.join(study, "out")
    path = os.path.join(study, "study.json")
    pn.run(path, out, "--no-figures", "--no-fit", "-q")
    cached = sorted(os.listdir(os.path.join(out, "cache")))
    pn.method("failing-in-study")(raises)
    with pytest.raises(RuntimeError, match="exited 1"):
        pn.run(path, out, "--no-figures", "--no-fit", "-q", extra_methods=["failing-in-study"])
    assert sorted(os.listdir(os.path.join(out, "cache"))) == cached
    status, stdout, _ = pn.cli("run", path, "-o", out, "--no-figures", "--no-fit", "-q",
                               "--add-method", "failing-in-study")
    assert status == 1
    assert 'user method "failing-in-study"' in stdout and "ValueError: no idea" in stdout, stdout


def test_add_method_refuses_what_it_cannot_measure(study):
    status, _, err = pn.cli("run", os.path.join(study, "study.json"), "-o",
                            os.path.join(study, "out"), "--add-method", "no-such-method")
    assert status == 2 and "--add-method" in err and '"no-such-method"' in err, err
