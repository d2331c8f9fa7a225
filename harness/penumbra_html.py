"""report.html of a Penumbra study, rendered from templates/report.html.j2.

The functions here turn the checked report (penumbra_data.Report) and the
figures drawn for it (penumbra_figures.report_figures) into a plain context
of strings, lists and dicts: tables as rows of cells, images as URLs
(linked or data: URIs: penumbra_data.PageImages), captions. All markup is in the templates,
and every string from report.json reaches the page through Jinja2's
autoescape, so it is escaped exactly once; nothing in the context is
marked safe.

The shapes of tables, figures and image grids are in penumbra_context.
"""
import math
import os

import jinja2

from penumbra_achievable_html import achievable_context
from penumbra_context import (
    ci_cell, figure, figure_file, grid_cell, table)
from penumbra_achievable import FIT_FILE
from penumbra_filtering_html import filtering_context, interplay_context
from penumbra_data import (
    METRICS, get_metric, metric_label, num, obj, objs, stem)
from penumbra_headline_html import (
    headline_context, lines_context, mean_rmse_context, provenance_context,
    variants_context)
from penumbra_grid_figure import bands, grid_renders
from penumbra_plot import replacing
from penumbra_lowpoly_html import lowpoly_context
from penumbra_tables import ranking_table, table_caption

TEMPLATES = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                         'templates')
VARIANT_METRICS = (               # (metric, scale, column head)
    ('profile.rmse_terminator', 100, 'terminator RMSE (%)'),
    ('profile.rmse_overall', 100, 'overall RMSE (%)'),
    ('profile.max_error_terminator', 100, 'max error (%)'),
    ('profile.max_step', 100, 'max step (%)'),
    ('profile.position_error_deg', 1, 'position error (deg)'),
    ('profile.width_deg', 1, 'width (deg)'),
    ('profile.lit_bias', 100, 'lit bias (%)'),
    ('view.rmse_grazing', 100, 'grazing-view RMSE (%)'),
    ('view.bias_grazing', 100, 'grazing-view bias (%)'),
    ('image.rmse', 1, 'image RMSE (W m⁻² sr⁻¹)'),
    ('image.ssim', 1, 'SSIM'),
    ('image.flip', 1, 'FLIP'))


def image_grid(var, uris, missing, renderers):
    """Every method's images, in bands of at most BAND_COLUMNS columns
    (ground truth, then methods; Chiang 2019, Fig. 4): per band, rows of
    renderers (image row, difference row, FLIP row) with something in it."""
    cols, renders = grid_renders(var, renderers)
    return [band_cells(bc, rs, uris, missing)
            for bc, rs in bands(cols, renders)]


def band_cells(cols, renders, uris, missing):
    """One band of the page's grid: {'cols', 'rows'} of grid cells."""
    def img(rel, alt, cap):
        return grid_cell(figure(uris[rel], alt, cap) if rel is not None
                         else None)
    rows = []
    for rend, rs in renders:
        rows.append({'head': rend, 'cells': [
            img(r.get('image'), f'{rend} {c}', f'{rend} / {c}') if r else
            grid_cell(na=missing.get((rend, c), 'not rendered'))
            for c, r in zip(cols, rs)]})
        for key, head, cap in (
                ('difference', 'difference', '{} − displacement ({})'),
                ('flip_map', 'FLIP', 'FLIP, {} against displacement ({})')):
            if any(r and r.get(key) is not None for r in rs):
                rows.append({'head': head, 'cells': [
                    img(r.get(key), f'{rend} {c} {head}', cap.format(c, rend))
                    if r else grid_cell() for c, r in zip(cols, rs)]})
    return {'cols': cols, 'rows': rows}


def metric_cell(comp, metric, scale):
    """A metric of a comparison, with its 95 % interval in the same cell
    where report.json has one (METRIC_ci), scaled as the column says."""
    section, _, name = metric.partition('.')
    ci = obj(comp.get(section)).get(name + '_ci')
    if isinstance(ci, list) and len(ci) == 2:
        return ci_cell(get_metric(comp, metric), ci, scale,
                       digits=2 if scale == 100 else 3)
    return (get_metric(comp, metric), scale)


def variant_context(var, report, figs, k, missing):
    """One variant's section (the k-th shown): image grid, profile
    figures, metrics table."""
    vid = str(var.get('id'))
    comps = [c for c in report.comps if c.get('variant') == var.get('id')]
    # "evaluator: displacement": a space lets the narrow column wrap there.
    rows = [[str(c.get('renderer')), str(c.get('method')),
             str(c.get('reference')).replace(':', ': ', 1)] +
            [metric_cell(c, m, s) for m, s, _ in VARIANT_METRICS]
            for c in comps]
    head = ['renderer', 'method', 'reference'] + [
        h for *_, h in VARIANT_METRICS]
    composed = [os.path.relpath(p, report.out) for p in figs['grids'][k]]
    return {'anchor': f'v-{stem(vid)}', 'id': vid,
            'label': str(var.get('label', '')),
            'grid': image_grid(var, report.uris, missing,
                               [str(r.get('id')) for r in report.renderers]),
            'composed': composed,
            'profiles': figure_file(
                figs['profiles'][k], f'profiles {vid}',
                f'figures/profiles-{stem(vid)}.{{png,svg,pdf}}: '
                f'{", ".join(figs["shown"])} (the highlighted methods); '
                f'every method: figures/all-methods-profiles-{stem(vid)}.png '
                f'(as PDF: report.py figure OUT --kind profile --variant {vid} '
                '--methods all -o FILE.pdf)'),
            'profiles_all': os.path.relpath(figs['profiles_all'][k],
                                            report.out),
            'metrics': table(head, rows) if rows else None}


def ranking_context(report):
    """The mean absolute error per method (report.json `ranking`), overall
    and per scene: NOT the ranking metric (statistics.notes says where and
    why it orders methods otherwise), in its metric's own unit."""
    rk = report.ranking
    name, unit = METRICS.get(rk.get('metric'), (rk.get('metric'), ''))
    head = ['method', f'mean absolute {name} ({unit}; not the ranking '
            'metric)', 'order', 'variants']
    return [{'title': str(group), 'table': table(head, [
        [str(e.get('method')), (e.get('mean'), 1),
         i + 1 if math.isfinite(num(e.get('mean'))) else None,
         e.get('count')] for i, e in enumerate(entries)])}
        for group, entries in report.ranking_groups() if entries]


def agreement_table(report):
    """The cross-renderer table: a row per external renderer, a column per
    render compared with the evaluator's (ground truth, then methods); each
    cell the mean terminator RMSE over variants in % with its interval."""
    ag = obj(report.doc.get('agreement'))
    sums = objs(ag.get('summaries'))
    if not sums:
        return None
    whats = list(dict.fromkeys(str(s.get('what')) for s in sums))
    names = {str(r.get('id')): f'{r.get("id")} ({r.get("version", "?")})'
             for r in report.renderers}
    at = {(str(s.get('renderer')), str(s.get('what'))): s for s in sums}
    rows = []
    for rend in dict.fromkeys(str(s.get('renderer')) for s in sums):
        cells = [names.get(rend, rend)]
        for w in whats:
            s = at.get((rend, w))
            cells.append(ci_cell(s.get('mean_rmse_terminator'), s.get('ci'),
                                 digits=2) if s else
                         {'text': 'not rendered', 'cls': 'na'})
        rows.append(cells)
    thr = num(ag.get('threshold'))
    return {'table': table(['renderer'] + whats, rows),
            'caption': 'Terminator-region profile RMSE of each renderer\'s '
                       'render against the evaluator\'s render of the same '
                       'scene and method, % of albedo·E/π, mean over variants '
                       'with its 95 % interval' + (
                           f'; agreement within {thr * 100:g} % is expected '
                           'of a correct renderer' if math.isfinite(thr)
                           else '') + '.'}


def statistics_context(report):
    """The findings in sentences (the overall ranking's), the
    cross-renderer table and the ground truth's convergence; None
    without statistics."""
    st = report.doc.get('statistics')
    if not isinstance(st, dict) or not isinstance(st.get('overall'), dict):
        return None
    methods = objs(st['overall'].get('methods'))
    agreement = obj(report.doc.get('agreement'))
    return {'sentences': [str(x) for x in st['overall'].get('headline')
                          or []],
            'agreement': [str(x) for x in agreement.get('headline') or []],
            'agreement_table': agreement_table(report),
            'ground_truth': ground_truth_context(report),
            'definition': str(st.get('definition', '')),
            'interval': str(st.get('interval', '')),
            'test': str(st.get('test', '')),
            'rejected': [f'{m.get("method")}: {m.get("rejected")}'
                         for m in methods if m.get('rejected')]}


def ground_truth_context(report):
    """The convergence of each variant's evaluator ground truth."""
    g = report.doc.get('ground_truth')
    if not isinstance(g, dict) or not objs(g.get('variants')):
        return None
    rows = []
    for v in objs(g.get('variants')):
        rows.append([str(v.get('variant')), str(v.get('label')),
                     (v.get('edge_length'), 1), v.get('spp') if type(v.get('spp')) is int
                     else 'n/a', (v.get('reached'), 1),
                     'yes' if v.get('converged') else 'NO: ' + str(v.get('why', '')),
                     str(len(objs(v.get('steps'))))])
    head = ['variant', 'scene and axes', 'edge length', 'spp',
            'change reached (fraction of albedo*E/pi)', 'converged', 'checks']
    return {'headline': str(g.get('headline', '')),
            'definition': str(g.get('definition', '')),
            'table': table(head, rows)}


def missing_what(m):
    """What a missing row leaves out: a method, a scene, or variants."""
    if 'variants' in m:
        v = [str(x) for x in m['variants']]
        shown = ', '.join(v[:6]) + (f', … ({len(v)} variants)' if len(v) > 6 else '')
        return f'every method in {shown}'
    if 'method' in m:
        return str(m['method'])
    return f'scene {m.get("scene", "")}' if 'scene' in m else ''


def renderer_tables(report):
    """The renderers, what they cannot provide, and what failed."""
    miss, fails = objs(report.doc.get('missing')), objs(
        report.doc.get('failures'))
    return {
        'renderers': table(['renderer', 'version', 'methods', 'note'], [
            [str(r.get('id')), str(r.get('version', '')),
             ', '.join(map(str, r.get('methods') or [])),
             str(r.get('note', ''))] for r in report.renderers]),
        'missing': table(['renderer', 'method', 'why'], [
            [str(m.get('renderer', '')), missing_what(m), str(m.get('why', ''))]
            for m in miss]) if miss else None,
        'failures': table(['render', 'error'], [
            [str(f.get('render', '')), str(f.get('error', ''))]
            for f in fails], 'fail') if fails else None}


def sweeps_context(report, sweeps):
    return [{'title': f'{metric_label(s["metric"])}, {s["renderer"]}',
             'figures': [figure_file(
                 f, f'plot {k} {scene}',
                 f'scene {scene}: {os.path.relpath(f, report.out)[:-4]}'
                 '.{png,svg,pdf}') for scene, f in s['scenes']]}
            for k, s in enumerate(sweeps)]


def report_context(report, figs):
    """The template context of the whole page."""
    rk, study, stats = report.ranking, report.study, figs['stats']
    name = str(study.get('name', 'study'))
    missing = {(str(m.get('renderer')), str(m.get('method'))):
               str(m.get('why', '')) for m in objs(report.doc.get('missing'))}
    return {
        'title': f'Penumbra report: {name}',
        'study': {'name': str(study.get('name', '')),
                  'file': str(study.get('file', ''))},
        'penumbra': str(report.doc.get('penumbra', '?')),
        'provenance': provenance_context(report.doc),
        'notices': [str(x) for x in report.doc.get('notices') or []
                    if isinstance(report.doc.get('notices'), list)],
        'headline': headline_context(report, stats),
        'ranking': {k: str(rk.get(k, '?'))
                    for k in ('metric', 'renderer', 'reference')},
        'mean_rmse': mean_rmse_context(report, stats, figs,
                                       ranking_context(report)),
        'statistics': statistics_context(report),
        'ranking_figure': figure_file(
            figs['ranking'], 'ranking',
            'figures/ranking.{png,svg,pdf}: ' + table_caption(
                stats, ranking_table(stats))) if figs['ranking'] else None,
        'statistics_figure': figure_file(
            figs['statistics'], 'combined error per scene',
            'figures/statistics.{png,svg,pdf}: combined error C per method '
            '(fraction of raw bump\'s; 1 = raw bump), overall and per '
            f'scene, with {stats.interval_text()}')
        if figs['statistics'] else None,
        'lines': lines_context(report, stats, figs),
        'shown_methods': figs['shown'],
        **renderer_tables(report),
        'variants': [variant_context(v, report, figs, k, missing)
                     for k, v in enumerate(report.shown)],
        'selection': variants_context(report),
        'sweeps': sweeps_context(report, figs['sweeps']),
        'has_plots': bool(report.doc.get('plots')),
        'lowpoly': lowpoly_context(report.lowpoly, figs['lowpoly'],
                                   report.out, report.src)
        if report.lowpoly else None,
        'filtering': filtering_context(report, figs),
        'interplay': interplay_context(report),
        'achievable': achievable_context(
            figs['achievable']['fit'], figs['achievable'], FIT_FILE),
        'terminator': [f'{t:g}' for t in report.terminator],
        'lit': [f'{t:g}' for t in report.lit],
        'image_unit': str(report.units.get('image', 'W m^-2 sr^-1'))}


def environment():
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(TEMPLATES), autoescape=True,
        undefined=jinja2.StrictUndefined)


def write_report(report, figs):
    """Render OUT/report.html (atomically: a reader never sees half a
    page); returns its path."""
    page = environment().get_template('report.html.j2').render(
        report_context(report, figs))
    path = os.path.join(report.out, 'report.html')
    with replacing(path) as tmp, open(tmp, 'w', encoding='utf-8') as f:
        f.write(page.rstrip('\n') + '\n')  # one final newline
    return path
