"""The bump-map filtering sections of report.html:
  filtering (templates/filtering.html.j2): per (map, run) entry of
    report.json's "filtering", the summary table of every roughness filter
    over levels >= 1 with its 95 % intervals, the findings in sentences, the
    chapter's claim per base roughness and the three metric figures
    (penumbra_filtering.py);
  interplay (templates/interplay.html.j2): the terminator RMSE of each
    method at each filter level against the map's displacement, with
    intervals, the truth's convergence check and the findings."""
from penumbra_context import ci_cell, figure_file, table
from penumbra_data import num, obj, objs
from penumbra_filtering import METRICS


def summary_table(doc):
    """One row per filter, lowest mean profile error first (as the
    experiment orders them)."""
    rows = []
    for s in objs(doc.get('summary')):
        cells = [str(s.get('filter'))]
        for metric, _, _ in METRICS:
            m = obj(s.get(metric))
            cells.append(ci_cell(m.get('mean'), m.get('interval'), scale=1.0,
                                 digits=3))
        cells.append(int(num(obj(s.get('profile_error')).get('n'))))
        rows.append(cells)
    return table(['filter', 'profile error (L2 / reference)',
                  'highlight width / reference', 'highlight energy / reference',
                  'footprints'], rows)


def claim_table(doc):
    """Per base roughness: levels where sigma^2 = 2 alpha^2 has the lower
    profile error, where sigma^2 = alpha^2 has, and ties."""
    per_alpha = {}
    for c in objs(doc.get('claim')):
        counts = per_alpha.setdefault(num(c.get('alpha')), [0, 0, 0])
        v = c.get('verdict')
        counts[0 if v == 'first lower' else 1 if v == 'second lower'
               else 2] += 1
    rows = [[f'{a:g}'] + counts for a, counts in sorted(per_alpha.items())]
    return table(['base GGX alpha', 'σ² = 2α² lower', 'σ² = α² lower',
                  'tied'], rows) if rows else None


def options_text(doc):
    o, src = obj(doc.get('options')), obj(doc.get('source'))
    size = src.get('size') if isinstance(src.get('size'), list) else ['?', '?']
    alphas = ', '.join(f'{num(a):g}' for a in o.get('alphas', []))
    return (f'{size[0]}×{size[1]} texels of {num(src.get("texel_size")):g} '
            f'scene units, edge {src.get("edge")}; levels 0 to '
            f'{int(num(o.get("levels"))) - 1} (1 to '
            f'{2 ** (int(num(o.get("levels"))) - 1)} texels per pixel side); '
            f'{o.get("footprints_per_level")} footprints per level '
            f'(seed {o.get("seed")}); base GGX alpha {alphas}; lookup '
            f'{o.get("lookup")}, pixel grid shifted {o.get("shift_pixels")} '
            f'pixel; view {num(o.get("view_deg")):g}°, light swept over '
            f'±{num(o.get("sweep_max_deg")):g}° in '
            f'{num(o.get("sweep_step_deg")):g}° steps')


def entry_context(entry, paths):
    doc = entry['doc']
    figures = [figure_file(paths[3 * k], f'{entry["map"]} {entry["run"]} '
                           f'{metric}', f'{label} against texels per pixel; '
                           'mean over footprints with its 95 % bootstrap '
                           f'interval (ideal: {ideal:g})')
               for k, (metric, label, ideal) in enumerate(METRICS)
               if 3 * k < len(paths)]
    return {'anchor': f'filtering-{entry["map"]}-{entry["run"]}',
            'title': f'{entry["map"]}, {entry["run"]}',
            'source': str(entry.get('source', '')),
            'options': options_text(doc),
            'compared_against': str(doc.get('compared_against', '')),
            'summary': summary_table(doc),
            'claim': claim_table(doc),
            'findings': [str(f) for f in doc.get('findings', [])],
            'files': f'{entry.get("json")}, {entry.get("csv")}',
            'figures': figures}


def filtering_context(report, figs):
    """The section's context, or None when the study has none."""
    if not report.filtering:
        return None
    return [entry_context(e, p)
            for e, p in zip(report.filtering, figs.get('filtering', []))]


def level_name(level):
    return 'unfiltered' if level is None else f'level {level}'


def interplay_context(report):
    """The interplay section's context, or None when the study has none."""
    ip = report.interplay
    if ip is None:
        return None
    methods = [str(m) for m in ip.get('methods', [])]
    cells = {(r.get('level'), r.get('method')): r for r in objs(ip.get('rows'))}
    rows = []
    for level in ip.get('levels', []):
        row = [level_name(level)]
        for m in methods:
            r = obj(cells.get((level, m)))
            row.append(ci_cell(r.get('rmse_terminator'), r.get('rmse_terminator_ci'),
                               scale=100.0, digits=2))
        rows.append(row)
    check = obj(ip.get('truth_check'))
    mp = obj(ip.get('map'))
    size = mp.get('size') if isinstance(mp.get('size'), list) else ['?', '?']
    return {'table': table(['filter level'] + [f'{m}: terminator RMSE (%)'
                                              for m in methods], rows),
            'scene': str(ip.get('scene', '')),
            'map': f'{mp.get("file")} ({size[0]}×{size[1]} texels)',
            'filter': str(ip.get('filter', '')),
            'compared_against': str(ip.get('compared_against', '')),
            'truth_check': ci_cell(check.get('rmse_terminator'),
                                   check.get('rmse_terminator_ci'),
                                   scale=100.0, digits=3)['text'],
            'finer_edge': f'{num(check.get("edge_length")):g}',
            'findings': [str(f) for f in ip.get('findings', [])]}
