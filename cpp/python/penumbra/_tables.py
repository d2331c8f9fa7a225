"""A finished study's metrics.csv and report.json as pandas DataFrames.

The types and units come from the files that document them,
harness/csv-columns.json and harness/report.schema.json, which the
study's writers are tested against; nothing here decides a unit.
"""

import json
import os

from . import _build

_CSV_DTYPES = {"string": "string", "integer": "Int64", "number": "float64"}


def _harness_file(name):
    with open(os.path.join(_build.DATA_DIR, "harness", name), encoding="utf-8") as f:
        return json.load(f)


def load_metrics(folder, file="metrics.csv"):
    """A study's metrics.csv (or metrics-long.csv, lowpoly.csv) as a DataFrame.

    One row per comparison, as written. dtypes from harness/csv-columns.json
    (docs/csv-columns.md): string columns ``string``, integers ``Int64``
    (nullable), numbers ``float64`` (an empty cell, an undefined quantity, is
    NaN); the sweep-axis columns, whose type depends on the study, as pandas
    infers them. ``df.attrs["units"]`` maps each documented column to its
    unit (None: an identifier or unitless), ``df.attrs["descriptions"]`` to
    its meaning; filter on ``truth`` before averaging (README, "Reading the
    outputs").
    """
    import pandas

    columns = [c for c in _harness_file("csv-columns.json")["files"][file]["columns"]
               if "name" in c]
    dtypes = {c["name"]: _CSV_DTYPES[c["type"]] for c in columns}
    path = os.path.join(folder, file)
    # keep_default_na=False: "none" and "NA" are method and scene names.
    # round_trip: the file's shortest decimal forms read back to their doubles
    # (pandas' default parser may miss by an ulp).
    df = pandas.read_csv(path, dtype=dtypes, keep_default_na=False, float_precision="round_trip",
                         na_values={
        name: [""] for name, dtype in dtypes.items() if dtype != "string"})
    df.attrs["source"] = os.path.abspath(path)
    df.attrs["units"] = {c["name"]: c["unit"] for c in columns if c["name"] in df.columns}
    df.attrs["descriptions"] = {c["name"]: c["description"] for c in columns
                                if c["name"] in df.columns}
    return df


def _descriptions(schema, definition, prefix=""):
    """Column name -> description of every leaf under a schema definition."""
    out = {}
    for key, node in schema["$defs"][definition].get("properties", {}).items():
        ref = node.get("$ref", "")
        target = ref.rsplit("/", 1)[-1]
        if ref and "properties" in schema["$defs"][target] and target != "interval":
            out.update(_descriptions(schema, target, f"{prefix}{key}."))
        else:
            out[prefix + key] = node.get("description", "")
    return out


def load_report(folder, section="comparisons"):
    """A study's report.json: one of its arrays as a DataFrame, the rest in attrs.

    section  "comparisons" (bump comparisons, one row each, the rows of
             metrics.csv in the same order) or "lowpoly" (its comparisons)

    Nested objects become dotted columns (``profile.rmse_terminator``);
    intervals stay [low, high] lists; null (undefined) is NaN.
    ``df.attrs["descriptions"]`` holds each column's description from
    harness/report.schema.json, which states its unit (e.g. "fraction of
    albedo*E/pi", "degrees"); ``df.attrs["report"]`` the whole document.
    """
    import pandas

    path = os.path.join(folder, "report.json")
    with open(path, encoding="utf-8") as f:
        report = json.load(f)
    rows = report["comparisons"] if section == "comparisons" else report["lowpoly"]["comparisons"]
    df = pandas.json_normalize(rows, sep=".")
    schema = _harness_file("report.schema.json")
    definition = "bump_comparison" if section == "comparisons" else "lowpoly_comparison"
    described = _descriptions(schema, definition)
    df.attrs["source"] = os.path.abspath(path)
    df.attrs["descriptions"] = {c: described[c] for c in df.columns if c in described}
    df.attrs["report"] = report
    return df
