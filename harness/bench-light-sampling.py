#!/usr/bin/python3
"""Benchmark: where multiple importance sampling (MIS) lowers the variance.

Renders the sphere weave (A = 0.01, raw bump) 64 x 64 under each area light
and environment of scenes/studies/lighting.json, and under three lights
chosen to be hard for the light's own sampler (a uniform white environment,
a 4 x 4 quad and a sphere of radius 1.5 each 0.2 from the sphere), with
`"sampling": "light"` and `"sampling": "mis"` at the same samples per pixel
(one shadow ray each), against a reference: the mean of both at 64 times
the samples (both are unbiased; the reference's own noise adds about 1/64
of the light sampler's error to both). Prints a Markdown table: the
relative mean squared error of each (over pixels, divided by the squared
mean lit radiance) and their ratio, with 95 % percentile-bootstrap
intervals over pixels (paired; 1,000 resamples, seed 1).
docs/evaluator.md#area-and-environment-lights quotes it.

    PYTHONPATH=build/python harness/bench-light-sampling.py --penumbra build/penumbra
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def lights(work, penumbra_module):
    study = json.load(open(os.path.join(ROOT, 'scenes/studies/lighting.json')))
    axis = next(a for a in study['axes'] if a.get('name') == 'lighting')
    out = [(v['id'], v['set']['/light']) for v in axis['values']
           if v['set']['/light']['type'] != 'distant']
    ones = np.ones((16, 32, 3), dtype=np.float32)
    white = os.path.join(work, 'white.exr')
    penumbra_module.write_exr(
        penumbra_module.Render(['R', 'G', 'B'], ones, {}), white)
    out += [('white environment', {'type': 'environment', 'map': white}),
            ('quad 4 x 4, 0.2 away',
             {'type': 'quad', 'corner': [-1.2, -2, -2], 'edge_u': [0, 4, 0],
              'edge_v': [0, 0, 4], 'radiance': 1}),
            ('sphere r = 1.5, 0.2 away',
             {'type': 'sphere', 'position': [-2.7, 0, 0], 'radius': 1.5,
              'radiance': 1})]
    return out


def render(args, penumbra_module, light, sampling, spp, out):
    light = dict(light, sampling=sampling)
    subprocess.run(
        [args.penumbra, 'render', os.path.join(ROOT, 'scenes/sphere-weave.json'),
         '-o', out, '-q', '--set', '/light=' + json.dumps(light),
         '--set', f'/camera/width={args.size}',
         '--set', f'/camera/height={args.size}',
         '--set', f'/camera/spp={spp}', '--set', '/camera/jitter=false'],
        check=True)
    return np.asarray(penumbra_module.read_exr(out)['R'], dtype=float).ravel()


def interval(values):
    return np.percentile(values, [2.5, 97.5])


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--penumbra', default=os.path.join(ROOT, 'build', 'penumbra'))
    p.add_argument('--size', type=int, default=64)
    p.add_argument('--spp', type=int, default=16)
    args = p.parse_args()
    import penumbra as penumbra_module
    rng = np.random.default_rng(1)
    print(f'sphere weave, raw bump, {args.size} x {args.size}, {args.spp} spp '
          f'against {64 * args.spp} spp; relative MSE [95 % interval]\n')
    print('| light | light sampler | MIS | MIS / light sampler |')
    print('|---|---|---|---|')
    with tempfile.TemporaryDirectory() as work:
        for name, light in lights(work, penumbra_module):
            out = os.path.join(work, 'r.exr')
            ref = 0.5 * sum(render(args, penumbra_module, light, s, 64 * args.spp, out)
                            for s in ('light', 'mis'))
            scale = ref[ref > 0].mean() ** 2
            err = {s: (render(args, penumbra_module, light, s, args.spp, out) - ref) ** 2 / scale
                   for s in ('light', 'mis')}
            n = ref.size
            idx = rng.integers(0, n, size=(1000, n))
            boot = {s: err[s][idx].mean(axis=1) for s in err}
            ratio = boot['mis'] / boot['light']
            cells = [f'{err[s].mean():.2e} [{interval(boot[s])[0]:.2e}, '
                     f'{interval(boot[s])[1]:.2e}]' for s in ('light', 'mis')]
            r = err['mis'].mean() / err['light'].mean()
            lo, hi = interval(ratio)
            print(f'| {name} | {cells[0]} | {cells[1]} | {r:.2f} [{lo:.2f}, {hi:.2f}] |',
                  flush=True)


if __name__ == '__main__':
    sys.exit(main())
