"""pn.run, pn.load_metrics and pn.load_report on a tiny evaluator-only study,
checked against the CSV and JSON files read without the module."""

import csv
import json
import math
import os
import shutil

import pytest

import penumbra as pn
from conftest import source


@pytest.fixture(scope="module")
def study():
    folder = "/tmp/penumbra-Python-study"
    shutil.rmtree(folder, ignore_errors=True)  # a fresh run, not a cached one
    os.makedirs(folder)
    path = os.path.join(folder, "study.json")
    with open(path, "w") as f:
        json.dump({
            "version": 1,
            "name": "python-tables",
            "scenes": [source("scenes", "calibration", "cylinder.json")],
            "set": {"/camera/width": 24, "/camera/height": 24, "/camera/spp": 2,
                    "/displacement/edge_length": 0.02},
            "axes": [{"pointer": "/height/amplitude", "label": "amplitude A (scene units)",
                      "values": [0.01, 0.02]}],
            "methods": ["none", "chiang2019", "estevez2019"],
            "renderers": ["evaluator"],
        }, f)
    out = os.path.join(folder, "out")
    pn.run(path, out, "--threads", "2")
    return out


def test_metrics_have_the_documented_types_and_units(study):
    df = pn.load_metrics(study)
    with open(os.path.join(study, "metrics.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(df) == len(rows) == 6  # 2 amplitudes x 3 methods, truth = own
    with open(source("harness", "csv-columns.json")) as f:
        documented = {c["name"]: c for c in json.load(f)["files"]["metrics.csv"]["columns"]
                      if "name" in c}
    wanted = {"string": "string", "integer": "Int64", "number": "float64"}
    for name, column in documented.items():
        assert str(df[name].dtype) == wanted[column["type"]], name
        assert df.attrs["units"][name] == column["unit"]
    for k, row in enumerate(rows):
        for name, column in documented.items():
            cell, value = row[name], df[name].iloc[k]
            if column["type"] == "string":
                assert value == cell, name
            elif cell == "":
                assert value is None or math.isnan(value), name
            else:
                assert float(value) == float(cell), name
    assert df.attrs["units"]["profile_rmse_terminator_rel"] == "fraction of albedo*E/pi"
    assert set(df["method"]) == {"none", "chiang2019", "estevez2019"}


def test_report_rows_are_the_metrics_rows(study):
    report = pn.load_report(study)
    metrics = pn.load_metrics(study)
    with open(os.path.join(study, "report.json")) as f:
        comparisons = json.load(f)["comparisons"]
    assert len(report) == len(comparisons) == len(metrics)
    assert list(report["variant"]) == list(metrics["variant"])
    for k, c in enumerate(comparisons):
        value = c["profile"]["rmse_terminator"]
        got = report["profile.rmse_terminator"].iloc[k]
        assert (value is None and math.isnan(got)) or got == value
    assert "albedo*E/pi" in report.attrs["descriptions"]["profile.rmse_terminator"]
