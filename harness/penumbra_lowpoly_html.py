"""The template context of report.html's low-poly section.

Built from penumbra_data.LowPoly and the figures penumbra_lowpoly_figures
drew for it; rendered by templates/lowpoly.html.j2. Tables, figures and
image grids have the shapes documented in penumbra_context; every string is
plain text for the template to escape.
"""
import math
import os

from penumbra_context import figure, figure_file, grid_cell, table
from penumbra_data import (
    LP_SIDE, LP_TRUTH, REF, data_uri, get_metric, inside, num, objs)

LP_UNITS = ('darkened_fraction', 'max_darkening', 'lost_shadow_fraction',
            'shadow_shift_px')
COMPARISON_METRICS = (            # (metric, scale, column head)
    ('shadow.darkened_fraction', 100, 'darkened (%)'),
    ('shadow.max_darkening', 100, 'max darkening (%)'),
    ('profile.rmse_terminator', 100, 'terminator RMSE (%)'),
    ('shadow.lost_shadow_fraction', 100, 'lost shadow (%)'),
    ('shadow.shadow_shift_px', 1, 'shadow shift (px)'),
    ('profile.position_error_deg', 1, 'position error (deg)'),
    ('image.rmse', 1, 'image RMSE'),
    ('image.ssim', 1, 'SSIM'),
    ('image.flip', 1, 'FLIP'))


def caption(path, floors, lp):
    """What a convergence or shadow figure's axes mean."""
    cap = f'figures/{os.path.basename(path)[:-4]}.{{png,svg,pdf}}. '
    if lp.log2_levels():
        cap += f'x: {lp.xlabel}, log₂ axis. '
    logs = [n for n, log, _ in floors if log]
    zeros = [n for n, _, zero in floors if zero]
    if logs:
        cap += 'Log y axis (' + ', '.join(logs) + ')'
        cap += ('; values of exactly 0 are drawn on the dotted floor line '
                '(' + ', '.join(zeros) + '). ') if zeros else '. '
    return cap + ('Offsets with equal values overlap: larger hollow markers '
                  'and thicker lines lie under smaller ones.')


def percent_interval(ci):
    lo, hi = (num(x) for x in (list(ci or []) + [None, None])[:2])
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return '–'
    return f'[{100 * lo:.2f}, {100 * hi:.2f}]'


def versus_best(e):
    vb = e.get('versus_best')
    if not isinstance(vb, dict):
        return 'the first'
    d = num(vb.get('mean_difference'))
    text = (f'{100 * d:+.2f} {percent_interval(vb.get("ci"))}'
            if math.isfinite(d) else '–')
    return f'{text}: ' + ('a tie' if vb.get('tie') else 'worse')


def rank_table(entries):
    vals = [num(e.get('darkened_fraction')) for e in entries]
    rows = []
    for e, v in zip(entries, vals):
        rank = 1 + sum(w < v for w in vals if math.isfinite(w)) \
            if math.isfinite(v) else None  # equal values share a rank
        rows.append([rank, str(e.get('offset')), (v, 100),
                     percent_interval(e.get('darkened_fraction_ci')),
                     versus_best(e),
                     (e.get('rmse_terminator'), 100), e.get('count')])
    return table(['rank', 'offset', 'mean darkened fraction (% of '
                          'lit pixels)', '95 % interval', 'minus the first '
                          '(paired, 95 %)', 'mean terminator profile RMSE (% of '
                          'albedo·E/π)', 'count'], rows)


def ranking_context(lp):
    rk = lp.ranking
    groups = [('overall', objs(rk.get('overall')))] + [
        (f'scene {s.get("scene")}', objs(s.get('offsets')))
        for s in objs(rk.get('per_scene'))]
    return {**{k: str(rk.get(k, '?'))
               for k in ('metric', 'renderer', 'reference')},
            'groups': [{'title': g, 'table': rank_table(e) if e else None}
                       for g, e in groups]}


def convergence_context(lp, figs):
    """Per group with figures: its convergence and external figures."""
    out = []
    for group in lp.groups:
        fs = [figure_file(figs[kind][group][0], f'{alt} {group}',
                 caption(*figs[kind][group], lp))
              for kind, alt in (('convergence', 'convergence'),
                                ('external', 'external renderers'))
              if group in figs[kind]]
        if fs:
            out.append({'group': group, 'figures': fs})
    return out


def shadow_context(lp, figs):
    """Per group with a cast shadow: its side-effect tables and figure."""
    out = []
    for group, (png, floors) in figs['shadow'].items():
        px = lp.cast_shadow_pixels(group)
        rows = {**lp.series(group, False), **lp.series(group, True)}
        tables = [table(
            [f'{pname} ({unit}); offset \\ {lp.xlabel}'] +
            [lp.level_text(t) for t in lp.levels],
            [[k[1] if k[0] == REF else f'{k[0]}: {k[1]}'] +
             [(v, scale) for v in s[metric]] for k, s in rows.items()])
            for metric, pname, unit, scale in LP_SIDE]
        out.append({'group': group,
                    'pixels': f'{px[0]}' + (f'–{px[-1]}' if len(px) > 1
                                            else ''),
                    'tables': tables,
                    'figure': figure_file(png, f'cast shadow {group}',
                                               caption(png, floors, lp))})
    return out


def image_grid(lp, var, uris):
    """Columns: the analytic truth, then each offset; rows: per renderer
    its images, then their differences from its analytic render and their
    FLIP maps against it."""
    renders = objs(var.get('renders'))
    at = {(str(r.get('renderer')), str(r.get('offset'))): r for r in renders}
    cols = list(dict.fromkeys([LP_TRUTH] + [
        o for o in lp.offsets if any(k[1] == o for k in at)] +
        [k[1] for k in at]))
    why = {(str(m.get('renderer')), str(m.get('offset'))): str(m.get('why'))
           for m in lp.missing if 'offset' in m}

    def tri(r):
        t = num(r.get('triangles'))
        return f', {t:.0f} triangles' if math.isfinite(t) else ''
    rows = []
    for rend in dict.fromkeys(lp.rend_ids + [k[0] for k in at]):
        rs = [at.get((rend, c)) for c in cols]
        if not any(rs):
            continue
        rows.append({'head': rend, 'cells': [grid_cell(figure(
            uris[r['image']], f'{rend} {c}', f'{rend} / {c}{tri(r)}'))
            if r and r.get('image') is not None else
            grid_cell(na=why.get((rend, c), 'not rendered'))
            for c, r in zip(cols, rs)]})
        for key, head, cap in (('difference', 'difference', '{} − analytic ({})'),
                               ('flip_map', 'FLIP', 'FLIP, {} against analytic ({})')):
            if any(r and r.get(key) is not None for r in rs):
                rows.append({'head': head, 'cells': [grid_cell(
                    figure(uris[r[key]], f'{rend} {c} {head}', cap.format(c, rend)))
                    if r and r.get(key) is not None else grid_cell()
                    for c, r in zip(cols, rs)]})
    return {'cols': ['analytic surface (truth)' if c == LP_TRUTH else c
                     for c in cols], 'rows': rows}


def _embed(v, uris, out, src):
    """Read a variant's images into uris (their page URLs), once each."""
    for r in objs(v.get('renders')):
        for key in ('image', 'difference', 'flip_map'):
            rel = r.get(key)
            if rel is not None and rel not in uris:
                ctx = f'lowpoly variant {v.get("id")}: {key}'
                uris[rel] = data_uri(inside(out, rel, src, ctx), src, ctx)


def images_context(lp, out, src):
    """The image grids of each group's two coarsest levels."""
    uris, scene_why, strips = {}, {}, []
    for m in lp.missing:
        if 'scene' in m:
            scene_why.setdefault(str(m.get('scene')), []).append(
                f'{m.get("renderer")}: {m.get("why")}')
    for group in lp.groups:
        vs = [v for v in lp.variants if lp.place(v)[0] == group and
              lp.level_index(v) is not None]
        first = sorted({lp.level_index(v) for v in vs})[:2]
        for v in sorted((v for v in vs if lp.level_index(v) in first),
                        key=lp.level_index):
            _embed(v, uris, out, src)
            why = scene_why.get(str(v.get('scene')))
            strips.append({'title': f'{v.get("id")}: '
                                    f'{v.get("label", group)}',
                           'grid': image_grid(lp, v, uris),
                           'not_rendered': '; '.join(why) if why else None})
    return strips


def renderers_context(lp):
    return {
        'renderers': table(['renderer', 'offsets'], [
            [str(r.get('id')), ', '.join(map(str, r.get('offsets') or []))]
            for r in lp.renderers]),
        'missing': table(['renderer', 'offset or scene', 'why'], [
            [str(m.get('renderer', '')),
             f'offset {m["offset"]}' if 'offset' in m else
             f'scene {m.get("scene", "")}', str(m.get('why', ''))]
            for m in lp.missing]) if lp.missing else None,
        'all_provided': bool(lp.renderers) and not lp.missing}


def comparisons_context(lp):
    """Per group, every comparison (shown folded)."""
    tris = {(str(v.get('id')), str(r.get('renderer')), str(r.get('offset'))):
            r.get('triangles') for v in lp.variants
            for r in objs(v.get('renders'))}
    head = ['renderer', 'offset', 'reference', lp.xlabel, 'triangles'] + [
        h for *_, h in COMPARISON_METRICS]
    out = []
    for group in lp.groups:
        cs = [c for c in lp.comps if lp.place(c)[0] == group]
        if not cs:
            continue
        # "evaluator: analytic", "epsilon (distance=0.01)": spaces let the
        # narrow columns wrap there.
        rows = [[str(c.get('renderer')),
                 str(c.get('offset')).replace('(', ' (', 1),
                 str(c.get('reference')).replace(':', ': ', 1),
                 lp.level_text(lp.place(c)[1]) if lp.place(c)[1] is not None
                 else 'n/a',
                 tris.get((str(c.get('variant')), str(c.get('renderer')),
                           str(c.get('offset'))))] +
                [(get_metric(c, m), s) for m, s, _ in COMPARISON_METRICS]
                for c in cs]
        out.append({'summary': f'{group}: {len(cs)} comparisons',
                    'table': table(head, rows)})
    return out


def lowpoly_context(lp, figs, out, src):
    """The whole low-poly section; figs: lowpoly_figures()'s result."""
    u = lp.units
    keys = [k for k in LP_UNITS if k in u] + sorted(
        k for k in u if k not in LP_UNITS)
    return {'units': [(str(k), str(u[k])) for k in keys],
            'ranking': ranking_context(lp),
            'numeric_axis': lp.conv is not None and lp.numeric,
            'convergence': convergence_context(lp, figs),
            'shadows': shadow_context(lp, figs),
            'images': images_context(lp, out, src),
            **renderers_context(lp),
            'comparisons': comparisons_context(lp),
            'has_comparisons': bool(lp.comps)}
