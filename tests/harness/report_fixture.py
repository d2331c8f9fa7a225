"""A synthetic study folder for the harness's tests: report.json (with the
fields of issue 37's contract, /work/notes/report-contract.md, or without
them, as an older report.json), tiny PNG images and nothing else.

The numbers are made up but shaped like a terminator study: 4 scenes x 3
amplitudes x 2 light directions x 3 materials = 72 variants; 22 methods
(more than any palette of 20); `chiang2019` helps at the largest amplitude
and hurts at the smallest (an interaction), `estevez2019` helps everywhere,
`cycles34` hurts everywhere. No randomness: every value is a function of the
variant's and the method's index, so the same call writes the same bytes.
"""
import json
import math
import os
import struct
import zlib

AMPLITUDES = [0.005, 0.01, 0.02]
LIGHTS = [[-1, 0, -0.2], [-1, 0, 0.4]]
LIGHT_LABELS = ['azimuth 101°, elevation 0°', 'azimuth 68°, elevation 0°']
SHADING = ['Lambert', 'Lambert + GGX (weight 0.4, alpha 0.3), factor on diffuse',
           'Lambert + GGX (weight 0.4, alpha 0.3), factor on all lobes']
SCENES = ['cylinder-grating', 'cylinder-weave', 'sphere-grating', 'sphere-weave']
METHODS = ['none', 'chiang2019', 'estevez2019', 'mitsuba3', 'shading-offset(s=0.3)',
           'cycles34'] + [f'method_{k:02d}' for k in range(6, 22)]
FRACTION = 'fraction of albedo*E/pi'


def png(path, rgb, size=8):
    """A size x size PNG of one colour (8-bit RGB), written by hand."""
    raw = b''.join(b'\x00' + bytes(rgb) * size for _ in range(size))

    def chunk(kind, data):
        body = kind + data
        return struct.pack('>I', len(data)) + body + struct.pack('>I', zlib.crc32(body))
    head = struct.pack('>IIBBBBB', size, size, 8, 2, 0, 0, 0)
    data = (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', head)
            + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))
    with open(path, 'wb') as f:
        f.write(data)


def factor(method, k, amp):
    """The method's error relative to raw bump (a ratio) at amplitude amp."""
    if method == 'none':
        return 1.0
    if method == 'chiang2019':       # helps at 0.02, hurts at 0.005
        return {0.005: 1.6, 0.01: 1.0, 0.02: 0.55}[amp]
    if method == 'estevez2019':
        return 0.7
    if method == 'cycles34':
        return 2.5
    return 0.75 + 0.03 * k


def variants(scenes=SCENES, lights=LIGHTS):
    out = []
    for s, scene in enumerate(scenes):
        for a, amp in enumerate(AMPLITUDES):
            for l, light in enumerate(lights):
                for m, shading in enumerate(SHADING):
                    out.append({'id': f'v{len(out):03d}', 'scene': scene,
                                'label': f'{scene}, A={amp}, {LIGHT_LABELS[l]}, {shading}',
                                'axis_values': [amp, light, shading],
                                'amp': amp, 'wiggle': ((s * 7 + a * 5 + l * 3 + m) % 5) / 50})
    return out


def profile(method, k, wiggle):
    f = factor(method, k, 0.01)
    vals = [max(0.0, math.cos(math.radians(t + 1)) - (0.0 if method == 'displacement' else
                                                       0.02 * f * math.sin(t / 9) * (1 + wiggle)))
            for t in range(0, 180, 2)]
    return {'bin_degrees': 2, 'value': [round(v, 6) for v in vals],
            'count': [10 if t < 120 else 0 for t in range(0, 180, 2)]}


def renders_and_comparisons(v, out, methods):
    renders, comps = [], []
    external = [m for m in ('none', 'chiang2019') if m in methods]
    for rend, meths in (('evaluator', methods), ('povray', external)):
        for rep, meth in [('displacement', 'none')] + [('bump', m) for m in meths]:
            name = f'images/{v["id"]}-{rend}-{rep}-{meth}'.replace('(', '_').replace(')', '_')
            png(os.path.join(out, name + '.png'), (120, 120, 120))
            r = {'renderer': rend, 'representation': rep, 'method': meth,
                 'image': name + '.png', 'difference': None, 'flip_map': None,
                 'profile': profile('displacement' if rep == 'displacement' else meth,
                                    methods.index(meth) if meth in methods else 0, v['wiggle'])}
            if rep == 'bump':
                png(os.path.join(out, name + '-diff.png'), (255, 200, 200))
                r['difference'] = name + '-diff.png'
                png(os.path.join(out, name + '-flip.png'), (60, 15, 100))
                r['flip_map'] = name + '-flip.png'
                f = factor(meth, methods.index(meth), v['amp'])
                term = 0.05 * (1 + v['wiggle']) * f
                comps.append({
                    'variant': v['id'], 'scene': v['scene'], 'renderer': rend,
                    'method': meth, 'reference': f'{rend}:displacement',
                    'profile': {'rmse_terminator': term,
                                'rmse_terminator_ci': [term * 0.9, term * 1.1],
                                'rmse_overall': term / 2, 'max_error_terminator': term * 2,
                                'max_step': 0.01, 'position_error_deg': 2 * f,
                                'width_deg': 10.0, 'lit_bias': 0.001},
                    'view': {'rmse_grazing': 0.02 * f * (1 + v['wiggle']),
                             'bias_grazing': -0.01},
                    'image': {'rmse': 0.01 * f, 'ssim': 0.95, 'mask_iou': 1.0,
                              'flip': 0.05 * f, 'flip_ci': [0.045 * f, 0.055 * f]}})
            renders.append(r)
    return renders, comps


def mean_ci(xs, widen=1.0):
    m = sum(xs) / len(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / max(1, len(xs) - 1)) / math.sqrt(len(xs))
    h = (2 * sd + 0.01) * widen
    return m, [m - h, m + h]


def ranking_stats(vs, methods, scene=None):
    """A RankingStats of the contract over the variants vs (groups by a
    simple rule of this fixture: within 0.1 of the group's leader)."""
    rows = []
    for k, m in enumerate(methods):
        cs = [factor(m, k, v['amp']) * (1 + 0.01 * (k % 3) * v['wiggle']) for v in vs]
        c, ci = mean_ci(cs)
        means = {'combined_relative_error': {'mean': c, 'ci': ci}}
        for key, unit_scale in (('profile.rmse_terminator', 0.05), ('view.rmse_grazing', 0.02),
                                ('profile.position_error_deg', 2.0), ('image.rmse', 0.01),
                                ('image.ssim', 0.9), ('image.flip', 0.05)):
            mm, mci = mean_ci([x * unit_scale for x in cs])
            means[key] = {'mean': mm, 'ci': mci}
        imp, ici = mean_ci([1 - x for x in cs])
        rows.append({'method': m, 'rank': 0, 'rejected': None, 'variants': len(vs),
                     'combined_relative_error': c, 'combined_ci': ci,
                     'terminator_improvement': imp, 'terminator_improvement_ci': ici,
                     'terminator_vs_none': {'better': sum(x < 1 for x in cs)},
                     'view_vs_none': {'mean_difference': 0.001 * k, 'ci': [0.0, 0.002 * k]},
                     'view_bias': -0.01, 'view_bias_ci': [-0.012, -0.008],
                     'means': means})
    rows.sort(key=lambda r: r['combined_relative_error'])
    group, leader = 0, None
    for r in rows:
        if leader is None or r['combined_relative_error'] - leader['combined_relative_error'] > 0.1:
            group, leader = group + 1, r
        d = r['combined_relative_error'] - leader['combined_relative_error']
        r.update(rank=group, group_leader=leader['method'],
                 versus_leader={'mean_difference': d, 'ci': [d - 0.05, d + 0.05],
                                'confidence': 0.9977})
    return {'scene': scene, 'variants': len(vs), 'confidence': 0.9977, 'methods': rows,
            'pairs': [], 'headline': [f'{rows[0]["method"]} has the lowest combined error.']}


def interaction_level(lv, method):
    """A level of an interaction entry: the method's C there and whether it
    helps (interval below 1), hurts (above) or ties."""
    r = next(r for r in lv['ranking']['methods'] if r['method'] == method)
    lo, hi = r['combined_ci']
    return {'value_label': lv['value_label'], 'value_id': lv['value_id'],
            'combined': r['combined_relative_error'], 'combined_ci': [lo, hi],
            'verdict': 'helps' if hi < 1 else 'hurts' if lo > 1 else 'tie'}


def by_axis(vs, methods, lights):
    axes = []
    for k, (pointer, label, values, labels, ids, numeric) in enumerate((
            ('/height/amplitude', 'amplitude A (scene units)', AMPLITUDES,
             [str(a) for a in AMPLITUDES], [str(a) for a in AMPLITUDES], True),
            ('/light/direction', 'light direction (towards the light)', lights,
             LIGHT_LABELS[:len(lights)], ['az101-el0', 'az68-el0'][:len(lights)], False),
            ('shading', 'material, and the lobes a factor scales', SHADING, SHADING,
             ['lambert', 'ggx-diffuse', 'ggx-all'], False))):
        levels = [{'value': val, 'value_label': lab, 'value_id': vid,
                   'ranking': ranking_stats([v for v in vs if v['axis_values'][k] == val], methods)}
                  for val, lab, vid in zip(values, labels, ids)]
        inter = [{'method': m, 'p': 0.0001 if m == 'chiang2019' and k == 0 else 0.5,
                  'p_holm': 0.002 if m == 'chiang2019' and k == 0 else 1.0,
                  'depends': m == 'chiang2019' and k == 0,
                  'levels': [interaction_level(lv, m) for lv in levels]}
                 for m in methods if m != 'none']
        axes.append({'pointer': pointer, 'label': label, 'numeric': numeric,
                     'levels': levels, 'interactions': inter})
    return axes


def statistics(vs, methods, new_fields, scenes, lights):
    st = {'definition': 'C = (E_term + E_view) / (E_term(none) + E_view(none))',
          'confidence': 0.95, 'interval': 'percentile bootstrap over variants',
          'test': 'sign test', 'baseline': 'none', 'reference': 'evaluator:displacement',
          'overall': ranking_stats(vs, methods),
          'per_scene': [ranking_stats([v for v in vs if v['scene'] == s], methods, s)
                        for s in scenes]}
    if new_fields:
        st.update({
            'primary_metric': {'id': 'combined_relative_error',
                               'name': 'combined error relative to raw bump',
                               'unit': "fraction of raw bump's E_term + E_view in the same "
                                       'variant (1 = raw bump, lower is better)'},
            'rule': 'A rank group is the best method not yet grouped and every later method '
                    'whose paired interval with it contains 0.',
            'by_axis': by_axis(vs, methods, lights),
            'headline': ['estevez2019 leads the best rank group.',
                         'At A = 0.02 chiang2019 removes 45 % [30, 60] of raw bump\'s error; '
                         'at A = 0.005 it adds 60 % [40, 80]: its benefit depends on amplitude.',
                         'cycles34 is worse than raw bump everywhere.'],
            'notes': ['The mean absolute terminator RMSE orders chiang2019 differently: it '
                      'averages absolute errors, which the largest amplitude dominates.']})
    else:
        for r in st['overall']['methods'] + [m for s in st['per_scene'] for m in s['methods']]:
            for key in ('group_leader', 'versus_leader', 'means'):
                r.pop(key)
        for s in [st['overall']] + st['per_scene']:
            s.pop('confidence')
    return st


def axes(new_fields, lights):
    out = [{'pointer': '/height/amplitude', 'label': 'amplitude A (scene units)',
            'values': AMPLITUDES, 'value_labels': [str(a) for a in AMPLITUDES]},
           {'pointer': '/light/direction', 'label': 'light direction (towards the light)',
            'values': lights, 'value_labels': LIGHT_LABELS[:len(lights)]},
           {'pointer': 'shading', 'label': 'material, and the lobes a factor scales',
            'values': SHADING, 'value_labels': SHADING}]
    if new_fields:
        for a, ids in zip(out, ([str(a) for a in AMPLITUDES], ['az101-el0', 'az68-el0'],
                                ['lambert', 'ggx-diffuse', 'ggx-all'])):
            a['value_ids'] = ids[:len(a['values'])]
    return out


def write_fixture(out, new_fields=True, with_none=True, name='fixture <b>&amp;',
                  scenes=SCENES, lights=LIGHTS, methods=METHODS):
    """Writes out/report.json and out/images/*.png; returns the document.
    A smaller study: fewer scenes, lights or methods (the first of each)."""
    os.makedirs(os.path.join(out, 'images'), exist_ok=True)
    methods = [m for m in methods if with_none or m != 'none']
    vs = variants(scenes, lights)
    comps, doc_vs = [], []
    for v in vs:
        renders, c = renders_and_comparisons(v, out, methods)
        comps += c
        doc_vs.append({'id': v['id'], 'scene': v['scene'], 'label': v['label'],
                       'axis_values': v['axis_values'], 'renders': renders})
    overall = {}
    for c in comps:
        if c['renderer'] == 'evaluator':
            overall.setdefault(c['method'], []).append(c['profile']['rmse_terminator'])
    doc = {
        'format': 'penumbra-report', 'version': 1, 'penumbra': '0.10.0',
        'study': {'name': name, 'file': 'studies/fixture.json'},
        'units': {'profile': FRACTION, 'terminator_region_deg': [60, 100],
                  'lit_region_deg': [0, 60], 'image': 'W m^-2 sr^-1'},
        'axes': axes(new_fields, lights),
        'renderers': [{'id': 'evaluator', 'version': '0.10.0', 'methods': methods, 'note': ''},
                      {'id': 'povray', 'version': '3.7',
                       'methods': [m for m in ('none', 'chiang2019') if m in methods],
                       'note': 'two methods'}],
        'variants': doc_vs, 'comparisons': comps,
        'ranking': {'metric': 'profile.rmse_terminator', 'reference': 'evaluator:displacement',
                    'renderer': 'evaluator', 'per_scene': [],
                    'overall': sorted(({'method': m, 'mean': sum(x) / len(x), 'count': len(x)}
                                       for m, x in overall.items()), key=lambda e: e['mean'])},
        'missing': [{'renderer': 'povray', 'method': 'estevez2019', 'why': 'not in POV-Ray'}],
        'failures': [], 'lowpoly': None, 'filtering': None, 'interplay': None,
        'plots': [{'metric': 'profile.rmse_terminator', 'x': 0, 'y': 1, 'kind': 'heatmap',
                   'renderer': 'evaluator'}]}
    if with_none:
        doc['statistics'] = statistics(vs, methods, new_fields, scenes, lights)
    if new_fields:
        doc['provenance'] = {'penumbra': '0.10.0', 'commit': 'a' * 40, 'dirty': False,
                             'date': '2026-11-27T06:00:00Z',
                             'machine': {'cpu': 'Test CPU <script>', 'cores': 2,
                                         'system': 'Linux 6.1 x86_64'},
                             'renderers': {'evaluator': '0.10.0', 'povray': '3.7.0.10'},
                             'study_sha256': 'b' * 64}
        doc['notices'] = [] if with_none else [
            'The study names no raw bump (`none`): its ranking is skipped.']
    with open(os.path.join(out, 'report.json'), 'w', encoding='utf-8') as f:
        json.dump(doc, f, indent=1)
    return doc
