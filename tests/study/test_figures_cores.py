#!/usr/bin/python3
"""The figure script draws the same bytes on one core as on several.

Usage: test_figures_cores.py PENUMBRA_BINARY SOURCE_DIR

harness/report.py sends independent figures (the ranking and statistics
figures, each variant's profiles and image grid, each scene's sweep, each
low-poly figure) to one worker process per core, or draws them itself on a
single core. Runs a small study with every kind of figure, then
`penumbra report` on copies of its folder twice: confined to one core (the
serial path) and on every core (the pool), and requires every file in
figures/ and report.html to be byte-identical between the two. Exit 77
(skipped) where this machine offers a single core: the pool cannot run.
"""
import filecmp
import json
import os
import shutil
import subprocess
import sys
import tempfile

from small_sections import small_lowpoly

BINARY, SOURCE = sys.argv[1], sys.argv[2]


def study():
    scenes = os.path.join(SOURCE, 'scenes')
    small = {'/camera/width': 24, '/camera/height': 24, '/camera/spp': 2}
    return {
        'version': 1, 'name': 'figures-cores',
        'scenes': [os.path.join(scenes, 'calibration', 'sphere.json'),
                   os.path.join(scenes, 'calibration', 'cylinder.json')],
        'set': dict(small, **{'/displacement/edge_length': 0.03}),
        'axes': [
            {'pointer': '/height/amplitude', 'values': [0.01, 0.02]},
            {'pointer': '/light/direction', 'values': [[-1, 0, -0.2], [-1, 0, 0.4]]}],
        'methods': ['none', 'chiang2019', {'id': 'shading-offset', 'parameters': {'s': 0.3}}],
        'renderers': ['evaluator'],
        'ground_truth': {'max_edge_refinements': 0, 'max_spp_refinements': 0},
        'plots': [{'metric': 'profile.rmse_terminator', 'x': '/height/amplitude',
                   'y': '/light/direction', 'kind': 'heatmap'}],
        'lowpoly': small_lowpoly(scenes, small)}


def report(folder, cores):
    """`penumbra report folder` confined to `cores`; the figures it wrote."""
    run = subprocess.run(['taskset', '-c', cores, BINARY, 'report', folder],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if run.returncode != 0:
        print(run.stdout)
        print(f'FAIL: penumbra report on cores {cores} exited {run.returncode}')
        sys.exit(1)
    # Not the stamp (figures/.inputs): it names the files by absolute path.
    return sorted(n for n in os.listdir(os.path.join(folder, 'figures')) if not n.startswith('.'))


def main():
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) < 2:
        print('SKIP: one core: the figure script has no pool to compare with')
        return 77
    tmp = tempfile.mkdtemp(prefix='penumbra-figures-cores.')
    try:
        path = os.path.join(tmp, 'study.json')
        with open(path, 'w') as f:
            json.dump(study(), f)
        out = os.path.join(tmp, 'out')
        run = subprocess.run([BINARY, 'run', path, '-o', out, '--no-figures'],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if run.returncode != 0:
            print(run.stdout)
            print(f'FAIL: penumbra run exited {run.returncode}')
            return 1
        one, many = os.path.join(tmp, 'one'), os.path.join(tmp, 'many')
        shutil.copytree(out, one, symlinks=True)
        shutil.copytree(out, many, symlinks=True)
        names = report(one, str(cores[0]))
        if report(many, ','.join(map(str, cores))) != names:
            print('FAIL: the two runs wrote different sets of figures')
            return 1
        for kind in ('ranking', 'statistics', 'profile', 'grid', 'plot-0-', 'lowpoly-'):
            if not any(n.startswith(kind) for n in names):
                print(f'FAIL: no {kind}* figure among {names}')
                return 1
        _, differ, errors = filecmp.cmpfiles(os.path.join(one, 'figures'),
                                             os.path.join(many, 'figures'), names, shallow=False)
        if not filecmp.cmp(os.path.join(one, 'report.html'), os.path.join(many, 'report.html'),
                           shallow=False):
            differ.append('report.html')
        if differ or errors:
            print(f'FAIL: {len(differ)} files differ ({differ[:5]}), {len(errors)} unreadable')
            return 1
        print(f'{len(names)} figures and report.html byte-identical on 1 and {len(cores)} cores')
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
