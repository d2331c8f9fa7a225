#!/usr/bin/python3
"""A small study's report.json, metrics.csv and lowpoly.csv against their docs
(its filtering and interplay sections' files: that they exist).

Usage: test_report_files.py PENUMBRA_BINARY SOURCE_DIR

Runs a tiny study (evaluator, plus POV-Ray when it is installed: then every
POV-Ray render is compared with two truths) into a temporary folder, then
checks that
  - report.json validates against harness/report.schema.json, and the schema
    rejects an undocumented key;
  - each CSV has one header line and exactly the columns that
    harness/csv-columns.json lists (axis columns by its naming rule), each
    cell of the documented type, empty only where the doc allows it;
  - rows match report.json's comparisons one to one, and no render is
    compared twice against the same kind of truth (column `truth`).
Exit 77 (skipped) only when python3-jsonschema is missing.
"""
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

from small_sections import small_lowpoly

try:
    import jsonschema
except ImportError:
    print('SKIP: python3-jsonschema is not installed')
    sys.exit(77)

BINARY, SOURCE = sys.argv[1], sys.argv[2]
HARNESS = os.path.join(SOURCE, 'harness')
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print('FAIL:', what, flush=True)


def tiny_study(with_povray):
    scene = os.path.join(SOURCE, 'scenes')
    small = {'/camera/width': 24, '/camera/height': 24, '/camera/spp': 2}
    return {
        'version': 1, 'name': 'report-files',
        'scenes': [os.path.join(scene, 'calibration', 'sphere.json')],
        'set': dict(small, **{'/displacement/edge_length': 0.03}),
        'axes': [
            {'pointer': '/height/amplitude', 'label': 'amplitude A (scene units)',
             'values': [0.01, 0.02]},
            {'pointer': '/light/direction', 'values': [[-1, 0, -0.2], [-1, 0.3, 0.4]]}],
        'methods': ['none', {'id': 'shading-offset', 'parameters': {'s': 0.3}}],
        'renderers': ['evaluator', 'povray'] if with_povray else ['evaluator'],
        'ground_truth': {'max_edge_refinements': 0, 'max_spp_refinements': 0},
        'lowpoly': small_lowpoly(scene, small),
        'filtering': {
            'maps': [{'name': 'noise', 'bake': os.path.join(scene, 'cylinder-noise.json'),
                      'size': 32}],
            'alphas': [0.2], 'filters': ['pixar2014', 'mip-only'], 'max_level': 2,
            'footprints': 4, 'sweep_step_deg': 4},
        'interplay': {
            'scene': os.path.join(scene, 'cylinder-grating.json'), 'size': 32,
            'levels': [None, 2], 'methods': ['none'],
            'set': dict(small, **{'/displacement/edge_length': 0.03})}}


def snake(pointer):
    """The documented rule (csv-columns.json, axis_columns.name)."""
    chars = ''.join(c.lower() if c.isascii() and c.isalnum() else '_' for c in pointer)
    return re.sub('_+', '_', chars).strip('_') or 'axis'


def axis_layout(values):
    """(type, suffixes) by the documented rule (axis_columns.types)."""
    vals = [v for v in values if v is not None]
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
        return 'number', ['']
    if all(isinstance(v, str) for v in vals):
        return 'string', ['']
    sizes = {len(v) for v in vals if isinstance(v, list)}
    if all(isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                       for x in v) for v in vals) and sizes in ({2}, {3}):
        return 'number', ['_x', '_y', '_z'][:sizes.pop()]
    return 'string', ['']


def expected_columns(doc_columns, axes):
    """[(name, type, may_be_empty)] in file order, axis columns expanded."""
    fixed = [c['name'] for c in doc_columns if 'name' in c]
    taken, out = set(fixed), []
    for c in doc_columns:
        if 'name' in c:
            out.append((c['name'], c['type'], 'empty' in c))
            continue
        for axis in axes:
            kind, suffixes = axis_layout(axis['values'])
            base = snake(axis['pointer'])
            while any(base + s in taken for s in suffixes):
                base += '_axis'
            for s in suffixes:
                taken.add(base + s)
                out.append((base + s, kind, any(v is None for v in axis['values'])))
    return out


def typed(cell, kind):
    if kind == 'string':
        return True
    try:
        if kind == 'integer':
            return str(int(cell)) == cell
        return math.isfinite(float(cell))
    except ValueError:
        return False


def check_csv(path, doc, axes, comparisons, method_key):
    with open(path, newline='', encoding='utf-8') as f:
        text = f.read()
    rows = list(csv.reader(text.splitlines(keepends=True)))
    header, body = rows[0], rows[1:]
    columns = expected_columns(doc['columns'], axes)
    name = os.path.basename(path)
    documented = [c[0] for c in columns]
    first = next((k for k, (a, b) in enumerate(zip(header, documented)) if a != b),
                 min(len(header), len(documented)))
    check(header == documented,
          f'{name}: header differs from csv-columns.json at column {first}: '
          f'written {header[first:first + 3]}, documented {documented[first:first + 3]}; '
          f'undocumented {sorted(set(header) - set(documented))}, '
          f'not written {sorted(set(documented) - set(header))}')
    check(len(set(header)) == len(header), f'{name}: duplicate column names')
    check(all(r != header for r in body), f'{name}: a second header line')
    check(len(body) == len(comparisons), f'{name}: {len(body)} rows, {len(comparisons)} comparisons')
    # Numbers are never quoted: a quote appears only around text with a comma.
    for line in text.splitlines()[1:]:
        for m in re.finditer(r'"([^"]*)"', line):
            check(not typed(m.group(1), 'number'), f'{name}: a quoted number {m.group(0)}')
    if header != documented:
        return []
    table = [dict(zip(header, r)) for r in body]
    for k, (col, kind, may_be_empty) in enumerate(columns):
        for r, row in enumerate(body):
            cell = row[k]
            if cell == '':
                check(may_be_empty, f'{name} row {r + 1}: {col} is empty, the doc says never')
            else:
                check(typed(cell, kind), f'{name} row {r + 1}: {col}={cell!r} is not {kind}')
        # A text column whose every cell is a number would be documented wrongly.
        cells = [row[k] for row in body if row[k] != '']
        check(kind != 'string' or not cells or not all(typed(c, 'number') for c in cells),
              f'{name}: {col} is documented as text but holds only numbers')
    # One to one with report.json, in the same order.
    for row, c in zip(table, comparisons):
        check(row['variant'] == c['variant'] and row[f'{method_key}_label'] == c[method_key] and
              row['renderer'] == c['renderer'] and
              f"{row['reference_renderer']}:{row['reference_representation']}" == c['reference'],
              f'{name}: row {row["variant"]} {row[method_key + "_label"]} does not match report.json')
        rmse = c['profile']['rmse_terminator']
        cell = row['profile_rmse_terminator_rel']
        check((cell == '' and rmse is None) or float(cell) == rmse,
              f'{name}: profile_rmse_terminator_rel {cell} != report.json {rmse}')
    # No render counted twice: one row per test render and kind of truth.
    keys = [(r['variant'], r['renderer'], r[f'{method_key}_label'], r['truth']) for r in table]
    check(len(set(keys)) == len(keys), f'{name}: a render appears twice against one truth')
    for r in table:
        own = r['reference_renderer'] == r['renderer']
        check(r['truth'] == ('own' if own else 'evaluator'), f'{name}: truth {r["truth"]} wrong')
        check(own or r['reference_renderer'] == 'evaluator', f'{name}: reference not evaluator')
        check(r[f'{method_key}_label'] == r[method_key] + (
            f"({r[method_key + '_params'].replace(';', ',')})" if r[method_key + '_params'] else ''),
            f'{name}: label, id and params disagree')
    return table


def check_long_csv(path, doc, axes, comparisons, wide):
    """metrics-long.csv: the documented header, one row per comparison and
    defined metric, each value equal to the wide file's, units as documented."""
    with open(path, newline='', encoding='utf-8') as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    documented = [c[0] for c in expected_columns(doc['columns'], axes)]
    check(header == documented, f'metrics-long.csv header {header} != documented {documented}')
    if header != documented:
        return
    wide_name = {'combined_relative_error': 'combined_relative_error',
                 'profile.rmse_terminator': 'profile_rmse_terminator_rel',
                 'view.rmse_grazing': 'view_rmse_grazing_rel',
                 'image.rmse': 'image_rmse_w_m2_sr',
                 'profile.position_error_deg': 'position_error_deg'}
    units = {'combined_relative_error': "fraction of raw bump's E_term + E_view in the same variant",
             'profile.rmse_terminator': 'fraction of albedo*E/pi', 'image.rmse': 'W m^-2 sr^-1',
             'profile.position_error_deg': 'degrees', 'image.ssim': 'unitless'}
    by_key = {(r['variant'], r['method_label'], r['renderer'],
               f"{r['reference_renderer']}:{r['reference_representation']}"): r for r in wide}
    seen = set()
    for r in (dict(zip(header, row)) for row in body):
        key = (r['variant'], r['method'], r['renderer'], r['reference'])
        check(key in by_key, f'metrics-long.csv row {key} has no comparison')
        seen.add(key)
        if r['metric'] in units:
            check(r['unit'] == units[r['metric']], f"unit of {r['metric']}: {r['unit']}")
        w = by_key.get(key, {}).get(wide_name.get(r['metric'], ''), None)
        if w is not None:
            check(w != '' and float(w) == float(r['value']),
                  f"metrics-long.csv {key} {r['metric']} = {r['value']}, metrics.csv {w}")
    check(len(seen) == len(comparisons), f'metrics-long.csv covers {len(seen)} of '
          f'{len(comparisons)} comparisons')


def check_light(table):
    for r in table:
        d = [float(r[f'light_direction_{c}']) for c in 'xyz']
        norm = math.sqrt(sum(x * x for x in d))
        elevation = math.degrees(math.asin(d[1] / norm))
        azimuth = math.degrees(math.atan2(d[0], -d[2]))
        check(abs(float(r['light_elevation_deg']) - elevation) < 1e-9 and
              abs(float(r['light_azimuth_deg']) - azimuth) < 1e-9,
              f'light angles {r["light_elevation_deg"]}, {r["light_azimuth_deg"]} for {d}')


def main():
    with_povray = shutil.which('povray') is not None
    tmp = tempfile.mkdtemp(prefix='penumbra-report-files.')
    try:
        study = os.path.join(tmp, 'study.json')
        with open(study, 'w') as f:
            json.dump(tiny_study(with_povray), f)
        out = os.path.join(tmp, 'out')
        run = subprocess.run([BINARY, 'run', study, '-o', out, '--jobs', '2', '--no-figures'],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if run.returncode != 0:
            print(run.stdout)
            print(f'FAIL: penumbra run exited {run.returncode}')
            return 1
        with open(os.path.join(out, 'report.json'), encoding='utf-8') as f:
            report = json.load(f)
        with open(os.path.join(HARNESS, 'report.schema.json'), encoding='utf-8') as f:
            schema = json.load(f)
        with open(os.path.join(HARNESS, 'csv-columns.json'), encoding='utf-8') as f:
            docs = json.load(f)

        jsonschema.Draft202012Validator.check_schema(schema)
        validator = jsonschema.Draft202012Validator(schema)
        for e in validator.iter_errors(report):
            check(False, f'report.json /{"/".join(map(str, e.absolute_path))}: {e.message[:300]}')
        report['comparisons'][0]['profile']['undocumented'] = 1
        check(not validator.is_valid(report), 'the schema accepts an undocumented key')
        del report['comparisons'][0]['profile']['undocumented']

        table = check_csv(os.path.join(out, 'metrics.csv'), docs['files']['metrics.csv'],
                          report['axes'], report['comparisons'], 'method')
        if table:
            check_long_csv(os.path.join(out, 'metrics-long.csv'),
                           docs['files']['metrics-long.csv'], report['axes'],
                           report['comparisons'], table)
        lowpoly = report['lowpoly']
        check_csv(os.path.join(out, 'lowpoly.csv'), docs['files']['lowpoly.csv'],
                  lowpoly['axes'], lowpoly['comparisons'], 'offset')
        for e in report['filtering']:
            check(os.path.isfile(os.path.join(out, e['json'])), f'no file {e["json"]}')
            check(os.path.isfile(os.path.join(out, e['csv'])), f'no file {e["csv"]}')
        check(len(report['filtering']) == 1, 'one filtering entry')
        check(len(report['interplay']['rows']) == 2, 'two interplay rows')
        for r in report['interplay']['rows']:
            check(os.path.isfile(os.path.join(out, r['image'])), f'no file {r["image"]}')
        if table:
            check_light(table)
            for r in table:
                check(os.path.isfile(os.path.join(out, r['exr'])), f'no file {r["exr"]}')
                check(os.path.isfile(os.path.join(out, r['reference_exr'])),
                      f'no file {r["reference_exr"]}')
                check((r['width_px'], r['height_px']) == ('24', '24'), 'resolution')
            check_flip(out, table[:3])
            check_flip_maps(out, report, table)
            truths = {r['truth'] for r in table}
            check(truths == ({'own', 'evaluator'} if with_povray else {'own'}), f'truths {truths}')
        print(f'{"FAILED" if failures else "ok"}: {len(failures)} failures '
              f'(POV-Ray {"included" if with_povray else "not installed"})')
        return 1 if failures else 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def check_flip(out, rows):
    """Mean FLIP in the CSV is what `penumbra compare --flip` (checked
    against NVlabs/flip's own values, tests/analysis/test_flip.cpp) gives for
    the same two renders, interval included."""
    for r in rows:
        run = subprocess.run(
            [BINARY, 'compare', os.path.join(out, r['reference_exr']),
             os.path.join(out, r['exr']), '--flip', '--json'],
            capture_output=True, text=True, check=False)
        check(run.returncode == 0, f'compare --flip exited {run.returncode}: {run.stderr[-300:]}')
        if run.returncode != 0:
            continue
        flip = json.loads(run.stdout)['flip']
        check(flip["range"] == "hdr", "HDR-FLIP on EXRs")
        for column, value in (('image_flip', flip['mean']),
                              ('image_flip_ci_low', flip['mean_ci'][0]),
                              ('image_flip_ci_high', flip['mean_ci'][1])):
            check(math.isclose(float(r[column]), value, rel_tol=1e-12, abs_tol=1e-15),
                  f'{column} {r[column]} against compare --flip {value}')


def check_flip_maps(out, report, rows):
    """Each render's FLIP map in the report is the PNG `penumbra compare
    --flip-map` draws for the render against its own renderer's truth
    (same bytes); truths have none."""
    maps, pictures = {}, []
    for v in report['variants'] + report['lowpoly']['variants']:
        for r in v['renders']:
            pictures += [r[k] for k in ('image', 'difference', 'flip_map') if r[k]]
            truth = r.get('representation') == 'displacement' or r.get('offset') == 'analytic'
            check((r['flip_map'] is None) == truth,
                  f'{r["exr"]}: flip_map {r["flip_map"]} (a truth has none, a test one)')
            maps[r['exr']] = r['flip_map']
    # A picture of one render never overwrites another's (a FLIP map named
    # NAME-flip.png was the preview of method mitsuba3-flip).
    check(len(set(pictures)) == len(pictures), 'two pictures share a file name')
    own = [r for r in rows if r['truth'] == 'own'][:3]
    check(len(own) == 3, 'three rows against their own renderer\'s truth')
    for k, r in enumerate(own):
        drawn = os.path.join(out, f'flip-check-{k}.png')
        run = subprocess.run(
            [BINARY, 'compare', os.path.join(out, r['reference_exr']),
             os.path.join(out, r['exr']), '--flip-map', drawn],
            capture_output=True, text=True, check=False)
        check(run.returncode == 0, f'compare --flip-map exited {run.returncode}: {run.stderr[-300:]}')
        study = maps.get(r['exr'])
        check(study is not None, f'{r["exr"]}: no flip_map in report.json')
        if run.returncode != 0 or study is None:
            continue
        with open(drawn, 'rb') as a, open(os.path.join(out, study), 'rb') as b:
            check(a.read() == b.read(), f'{study} differs from compare --flip-map\'s')


if __name__ == '__main__':
    sys.exit(main())
