"""pn.factor against the command line's factors and the papers' formulas."""

import csv
import json
import math
import os

import numpy as np
import pytest

import penumbra as pn
from conftest import cli, source

TERMINATOR_METHODS = [m for m in pn.methods() if m["kind"] == "terminator"]
# fitted reads a table file and python stands for the user methods (test_user_methods.py);
# the others need nothing beyond their defaults.
PLAIN = [m["id"] for m in TERMINATOR_METHODS if m["id"] not in ("fitted", "python")]


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def contour(tmp_path_factory):
    """`penumbra contour` for every method: G on its grid, as the CLI computes it.

    Its geometry (analysis/contour.h): Ng = z, wi = (sin t, 0, cos t),
    Ns = (sin d, 0, cos d), wo = Ng; the grid includes the degenerate rows
    and columns (no deviation, grazing light at t = 90 degrees)."""
    folder = "/tmp/penumbra-Python-contour"
    args = ["contour", "-o", folder, "--step", "10"]
    for m in PLAIN:
        args += ["--method", m]
    cli(*args)
    rows = {}
    with open(os.path.join(folder, "contour.csv"), newline="") as f:
        for r in csv.DictReader(f):
            rows.setdefault(r["method"], []).append(
                (float(r["light_deg"]), float(r["deviation_deg"]), float(r["G"])))
    return rows


@pytest.mark.parametrize("method", PLAIN)
def test_factor_equals_contour_bits(method, contour):
    rows = contour[method]
    # The grid's vectors as core/vec.h's radians() and the C library's sin
    # and cos make them (NumPy's vectorised sin may round differently).
    def direction(deg):
        r = deg * (math.pi / 180.0)
        return [math.sin(r), 0.0, math.cos(r)]

    expected = np.array([r[2] for r in rows])
    ng = np.tile([0.0, 0.0, 1.0], (len(rows), 1))
    wi = np.array([direction(r[0]) for r in rows])
    ns = np.array([direction(r[1]) for r in rows])
    g = pn.factor(method, ng, ns, wi)
    # The CLI prints the shortest text that reads back to the same double:
    # equal bits, NaN where both say the factor is undefined.
    np.testing.assert_array_equal(g, expected)


def estevez2019_reference(ng, ns, wi):
    """Ray Tracing Gems ch. 12, Listing 12-1, written from the paper."""
    cos_d = np.minimum(np.abs(np.sum(ng * ns, axis=1)), 1.0)
    tan2_d = (1.0 - cos_d * cos_d) / (cos_d * cos_d)
    alpha2 = np.clip(0.125 * tan2_d, 0.0, 1.0)
    cos_i = np.maximum(np.abs(np.sum(ng * wi, axis=1)), 1e-6)
    tan2_i = (1.0 - cos_i * cos_i) / (cos_i * cos_i)
    return 2.0 / (1.0 + np.sqrt(1.0 + alpha2 * tan2_i))


def chiang2019_reference(ng, ns, wi):
    """Chiang, Li, Burley 2019, eqs. (1)-(2), written from the talk."""
    g = np.minimum(1.0, np.sum(ng * wi, axis=1) /
                   (np.sum(ns * wi, axis=1) * np.sum(ng * ns, axis=1)))
    g = np.clip(g, 0.0, 1.0)
    return -g ** 3 + g ** 2 + g


def random_lit_points(n, seed):
    """Ng, a bumped Ns within 60 degrees of it, wi lit by both (the region
    where the formulas have no clamps to disagree on)."""
    rng = np.random.default_rng(seed)
    ng = unit(rng.normal(size=(n, 3)))
    ns = unit(ng + 0.8 * unit(rng.normal(size=(n, 3))))
    wi = unit(rng.normal(size=(n, 3)))
    keep = (np.sum(ng * wi, 1) > 0.01) & (np.sum(ns * wi, 1) > 0.01) & (np.sum(ng * ns, 1) > 0.5)
    return ng[keep], ns[keep], wi[keep]


@pytest.mark.parametrize("method,reference", [("estevez2019", estevez2019_reference),
                                              ("chiang2019", chiang2019_reference)])
def test_factor_matches_the_papers_on_random_directions(method, reference):
    ng, ns, wi = random_lit_points(20000, 44)
    assert len(ng) > 2000
    # The C++ clamps and orders its products differently: a few ulps apart.
    np.testing.assert_allclose(pn.factor(method, ng, ns, wi), reference(ng, ns, wi),
                               rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("method", PLAIN)
def test_factor_on_degenerate_and_random_directions(method):
    """Finite for every unit input (core/terminator.h), within [0, 1] for the
    plain factors, and 1 without deviation where the registry says so."""
    info = next(m for m in TERMINATOR_METHODS if m["id"] == method)
    rng = np.random.default_rng(7)
    n = 4000
    ng = unit(rng.normal(size=(n, 3)))
    ns = unit(rng.normal(size=(n, 3)))
    wi = unit(rng.normal(size=(n, 3)))
    wo = unit(rng.normal(size=(n, 3)))
    # Degenerate rows: Ns = Ng (exactly unit: z), wi = Ng, wi perpendicular
    # to Ng, Ns = -Ng.
    perpendicular = unit(np.cross(ng, [0.0, 0.0, 1.0]))
    ng[:100] = [0.0, 0.0, 1.0]
    ns[:100] = ng[:100]
    wi[100:200] = ng[100:200]
    wi[200:300] = perpendicular[200:300]
    ns[300:400] = -ng[300:400]
    g = pn.factor(method, ng, ns, wi, wo)
    assert g.shape == (n,) and g.dtype == np.float64
    if info["family"] == "factor":
        assert np.all(np.isfinite(g)) and np.all((g >= 0) & (g <= 1))
    lit = np.sum(ng[:100] * wi[:100], 1) > 0
    if info["identity_without_deviation"] and info["family"] == "factor":
        np.testing.assert_array_equal(g[:100][lit], 1.0)


def test_parameters_are_checked_as_in_a_scene():
    ng = np.array([[0.0, 0.0, 1.0]])
    wi = unit(np.array([[1.0, 0.0, 0.2]]))
    plain = pn.factor("shading-offset", ng, ng, wi)
    offset = pn.factor("shading-offset", ng, ng, wi, s=0.5)
    # s = 0 is the identity (the registry says so); s > 0 darkens.
    assert plain[0] == 1.0 and 0.0 <= offset[0] < 1.0
    with pytest.raises(pn.SceneError) as e:
        pn.factor("shading-offset", ng, ng, wi, s=1.5)
    assert (e.value.file, e.value.pointer) == ("pn.factor", "/terminator/parameters/s")
    assert "[0, 1]" in e.value.reason
    with pytest.raises(pn.SceneError) as e:
        pn.factor("no-such-method", ng, ng, wi)
    assert e.value.pointer == "/terminator/method" and "chiang2019" in e.value.reason
    with pytest.raises(ValueError):
        pn.factor("chiang2019", ng, np.zeros((2, 3)), wi)


def test_methods_is_the_cli_registry():
    import json
    _, out, _ = cli("methods", "--json")
    assert pn.methods() == json.loads(out)
    assert math.isclose(next(p for m in pn.methods() if m["id"] == "shading-offset"
                             for p in m["parameters"])["max"], 1.0)


def test_a_plain_factor_ignores_the_material_and_a_model_does_not():
    rng = np.random.default_rng(5)
    n = 500
    ng = np.tile([0.0, 0.0, 1.0], (n, 1))
    ns = unit(rng.normal(size=(n, 3)) * [0.4, 0.4, 0.0] + ng)
    wi = unit(rng.normal(size=(n, 3)) + [0.0, 0.0, 0.3])
    wo = unit(rng.normal(size=(n, 3)) * [1.0, 1.0, 0.0] + ng)
    glossy = {"albedo": 0.8, "specular": {"weight": 0.5, "roughness": 0.3}}
    # G of a plain factor is a function of the vectors alone.
    for method in ("estevez2019", "chiang2019", "deshmukh2020"):
        np.testing.assert_array_equal(pn.factor(method, ng, ns, wi, wo, material=glossy),
                                      pn.factor(method, ng, ns, wi, wo))
    # A microfacet model's effective factor is its radiance over raw bump's,
    # which a glossy lobe changes.
    lambert = pn.factor("schuessler2017", ng, ns, wi, wo)
    mixed = pn.factor("schuessler2017", ng, ns, wi, wo, material=glossy)
    lit = np.isfinite(lambert) & np.isfinite(mixed)
    assert lit.sum() > 100 and np.max(np.abs(lambert[lit] - mixed[lit])) > 1e-3
    with pytest.raises(pn.SceneError) as e:
        pn.factor("estevez2019", ng, ns, wi, material={"albedo": 2})
    assert (e.value.file, e.value.pointer) == ("pn.factor", "/material/albedo")


def test_fitted_is_its_table_at_the_cells_centres():
    # tests/evaluator/data/fitted-table.json: light cells 30 degrees wide from
    # 0, deviation cells from 0; values with light fastest.
    table = source("tests", "evaluator", "data", "fitted-table.json")
    with open(table) as f:
        values = json.load(f)["values"]
    ng, ns, wi = [], [], []
    for d in (15.0, 45.0):
        for t in (15.0, 45.0, 75.0):
            ng.append([0.0, 0.0, 1.0])
            ns.append([math.sin(math.radians(d)), 0.0, math.cos(math.radians(d))])
            wi.append([-math.sin(math.radians(t)), 0.0, math.cos(math.radians(t))])
    g = pn.factor("fitted", np.array(ng), np.array(ns), np.array(wi), table=table)
    np.testing.assert_allclose(g, values, rtol=0, atol=1e-12)


def hanika2021(v, m, b):
    """Hanika 2021 ("Hacking the Shadow Terminator", Ray Tracing Gems II
    ch. 4): P' = P - sum_k b_k min(0, <P - v_k, n_k>) n_k."""
    p = np.einsum("ij,ijk->ik", b, v)
    d = np.einsum("ijk,ijk->ij", p[:, None, :] - v, m)
    return p - np.einsum("ij,ijk->ik", b * np.minimum(0.0, d), m)


def test_offsets_on_arrays_follow_their_formulas():
    # Triangles of a unit sphere tessellated coarsely, vertex normals radial,
    # hit at random barycentrics, lights above the shading normal.
    rng = np.random.default_rng(9)
    n = 400
    centre = unit(rng.normal(size=(n, 3)))
    v = unit(centre[:, None, :] + 0.35 * rng.normal(size=(n, 3, 3)))
    flip = np.einsum("ij,ij->i", np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), centre) < 0
    v[flip] = v[flip][:, ::-1]  # wind every triangle outwards
    m = v.copy()  # on a unit sphere the vertex normal is the vertex
    b = rng.dirichlet([1.0, 1.0, 1.0], size=n)
    wi = unit(centre + 0.5 * rng.normal(size=(n, 3)))
    p = np.einsum("ij,ijk->ik", b, v)
    ng = unit(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]))
    origins, skip = pn.offset("none", v, m, b, wi)
    np.testing.assert_array_equal(origins, p)
    assert skip.all()
    origins, _ = pn.offset("hanika2021", v, m, b, wi)
    np.testing.assert_allclose(origins, hanika2021(v, m, b), rtol=0, atol=1e-12)
    origins, _ = pn.offset("epsilon", v, m, b, wi, distance=0.01)
    above = np.einsum("ij,ij->i", ng, wi) > 0
    np.testing.assert_allclose(origins[above], p[above] + 0.01 * ng[above], rtol=0, atol=1e-12)
    with pytest.raises(pn.SceneError) as e:
        pn.offset("no-such-offset", v, m, b, wi)
    assert e.value.pointer == "/offset/method"


def test_an_adjustment_on_none_is_the_method_that_brings_it():
    # iray2017 and unity-hdrp are normal adjustments alone in the method
    # table (kind "adjustment"): the adjustment on `none` is the method.
    rng = np.random.default_rng(11)
    n = 300
    ng = np.tile([0.0, 0.0, 1.0], (n, 1))
    ns = unit(rng.normal(size=(n, 3)) * [0.5, 0.5, 0.0] + ng)
    wi = unit(rng.normal(size=(n, 3)) + [0.0, 0.0, 0.2])
    wo = unit(rng.normal(size=(n, 3)) * [1.0, 1.0, 0.0] + ng)
    for id in ("iray2017", "unity-hdrp"):
        np.testing.assert_array_equal(pn.factor("none", ng, ns, wi, wo, adjustment=id),
                                      pn.factor(id, ng, ns, wi, wo))
    with pytest.raises(pn.SceneError) as e:
        pn.factor("none", ng, ns, wi, adjustment="no-such-adjustment")
    assert e.value.pointer == "/terminator/normal_adjustment"
