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

from penumbra_context import (
    ci_cell, figure, figure_file, grid_cell, table)
from penumbra_filtering_html import filtering_context, interplay_context
from penumbra_data import (
    FRACTION, GROUND_TRUTH, METRICS, column, get_metric, metric_label, num,
    obj, objs, stem)
from penumbra_lowpoly_html import lowpoly_context

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
    ('image.ssim', 1, 'SSIM'))


def image_grid(var, uris, missing, renderers):
    """Rows: renderers (image row, then difference row); columns: ground
    truth, then methods (Chiang 2019, Fig. 4)."""
    renders = objs(var.get('renders'))
    cols = list(dict.fromkeys([GROUND_TRUTH] + [column(r) for r in renders]))
    at = {(str(r.get('renderer')), column(r)): r for r in renders}

    def img(rel, alt, cap):
        return grid_cell(figure(uris[rel], alt, cap) if rel is not None
                         else None)
    rows = []
    for rend in dict.fromkeys(renderers + [k[0] for k in at]):
        rs = [at.get((rend, c)) for c in cols]
        if not any(rs):
            continue
        rows.append({'head': rend, 'cells': [
            img(r.get('image'), f'{rend} {c}', f'{rend} / {c}') if r else
            grid_cell(na=missing.get((rend, c), 'not rendered'))
            for c, r in zip(cols, rs)]})
        if any(r and r.get('difference') is not None for r in rs):
            rows.append({'head': 'difference', 'cells': [
                img(r.get('difference'), f'{rend} {c} difference',
                    f'{c} − displacement ({rend})') if r else grid_cell()
                for c, r in zip(cols, rs)]})
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


def variant_context(var, report, fig, missing, grid=()):
    """One variant's section: image grid, profile figure, metrics table."""
    vid = str(var.get('id'))
    comps = [c for c in report.comps if c.get('variant') == var.get('id')]
    # "evaluator: displacement": a space lets the narrow column wrap there.
    rows = [[str(c.get('renderer')), str(c.get('method')),
             str(c.get('reference')).replace(':', ': ', 1)] +
            [metric_cell(c, m, s) for m, s, _ in VARIANT_METRICS]
            for c in comps]
    head = ['renderer', 'method', 'reference'] + [
        h for *_, h in VARIANT_METRICS]
    return {'anchor': f'v-{stem(vid)}', 'id': vid,
            'label': str(var.get('label', '')),
            'grid': image_grid(var, report.uris, missing,
                               [str(r.get('id')) for r in report.renderers]),
            'composed': [os.path.relpath(p, report.out) for p in grid],
            'profiles': figure_file(
                fig, f'profiles {vid}',
                f'figures/profiles-{stem(vid)}.{{png,svg,pdf}}'),
            'metrics': table(head, rows) if rows else None}


def ranking_context(report):
    """The headline: ranking tables (overall, per scene)."""
    rk = report.ranking
    name, unit = METRICS.get(rk.get('metric'), (rk.get('metric'), ''))
    scale = 100 if unit == FRACTION else 1
    head = ['method', f'mean {name} ({"%" if scale == 100 else unit})',
            'rank', 'count']
    return [{'title': str(group), 'table': table(head, [
        [str(e.get('method')), (e.get('mean'), scale),
         i + 1 if math.isfinite(num(e.get('mean'))) else None,
         e.get('count')] for i, e in enumerate(entries)])}
        for group, entries in report.ranking_groups() if entries]


def verdict(m):
    """Better, worse or tied with raw bump: whether the combined relative
    error's 95 % interval lies below 1, above 1, or contains it."""
    if m.get('method') == 'none':
        return 'baseline'
    ci = m.get('combined_ci')
    if not isinstance(ci, list) or len(ci) != 2 or None in ci:
        return 'n/a'
    lo, hi = num(ci[0]), num(ci[1])
    return 'better' if hi < 1 else 'worse' if lo > 1 else 'tie'


def statistics_rows(methods):
    """The headline table's rows: every number in percent with its 95 %
    interval in the same cell."""
    rows = []
    for m in methods:
        term, view = m.get('terminator_vs_none') or {}, m.get('view_vs_none') or {}
        label = str(m.get('method'))
        if m.get('rejected'):
            label += ' (rejected)'
        rows.append([
            m.get('rank'), label, verdict(m),
            ci_cell(m.get('combined_relative_error'), m.get('combined_ci')),
            ci_cell(m.get('terminator_improvement'),
                    m.get('terminator_improvement_ci'), digits=0),
            f'{term.get("better", 0)}/{m.get("variants", 0)}',
            ci_cell(view.get('mean_difference'), view.get('ci'), digits=2),
            ci_cell(m.get('view_bias'), m.get('view_bias_ci'), digits=2)])
    return rows


STATISTICS_HEAD = [
    'rank', 'method', 'vs raw bump', 'combined error (% of raw bump’s) [95 % CI]',
    'terminator RMSE removed (%) [95 % CI]', 'better than raw bump (variants)',
    'grazing-view RMSE minus raw bump (% of albedo·E/π) [95 % CI]',
    'grazing-view signed error (% of albedo·E/π) [95 % CI]']


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
    """The headline: a lead sentence, the method table and the
    cross-renderer table (every number in % with its 95 % interval), then
    the same findings in sentences; methods the literature rejects
    labelled."""
    st = report.doc.get('statistics')
    if not isinstance(st, dict) or not isinstance(st.get('overall'), dict):
        return None
    overall = st['overall']
    methods = objs(overall.get('methods'))
    rows = statistics_rows(methods)
    rejected = [f'{m.get("method")}: {m.get("rejected")}'
                for m in methods if m.get('rejected')]
    agreement = obj(report.doc.get('agreement'))
    sentences = [str(x) for x in overall.get('headline') or []]
    return {'lead': sentences[0] if sentences else '',
            'sentences': sentences[1:],
            'agreement': [str(x) for x in agreement.get('headline') or []],
            'agreement_table': agreement_table(report),
            'ground_truth': ground_truth_context(report),
            'table': table(STATISTICS_HEAD, rows) if rows else None,
            'definition': str(st.get('definition', '')),
            'interval': str(st.get('interval', '')),
            'test': str(st.get('test', '')),
            'rejected': rejected}


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


def variants_note(report):
    """Says which variants have a section when not all of them do."""
    n, k = len(report.variants), len(report.shown)
    if k == n:
        return None
    return (f'{n} variants: the {k} sections below show variants evenly '
            f'spaced over the study\'s order (the first and the last '
            f'included). Every variant\'s numbers are in metrics.csv and '
            f'report.json; the ranking, statistics and sweeps above and '
            f'below use them all.')


def report_context(report, figs):
    """The template context of the whole page."""
    rk, study = report.ranking, report.study
    name = str(study.get('name', 'study'))
    missing = {(str(m.get('renderer')), str(m.get('method'))):
               str(m.get('why', '')) for m in objs(report.doc.get('missing'))}
    ranking_fig = figs['ranking']
    stats_fig = figs.get('statistics')
    return {
        'title': f'Penumbra report: {name}',
        'study': {'name': str(study.get('name', '')),
                  'file': str(study.get('file', ''))},
        'penumbra': str(report.doc.get('penumbra', '?')),
        'ranking': {k: str(rk.get(k, '?'))
                    for k in ('metric', 'renderer', 'reference')},
        'ranking_tables': ranking_context(report),
        'statistics': statistics_context(report),
        'ranking_figure': figure_file(
            ranking_fig, 'ranking', 'figures/ranking.{png,svg,pdf}')
        if ranking_fig else None,
        'statistics_figure': figure_file(
            stats_fig, 'combined relative error with 95 % intervals',
            'figures/statistics.{png,svg,pdf}: combined error per method in % '
            'of raw bump\'s, with its 95 % bootstrap interval over variants '
            '(dashed: raw bump, 100 %)') if stats_fig else None,
        **renderer_tables(report),
        'variants': [variant_context(v, report, f, missing, g)
                     for v, f, g in zip(report.shown, figs['profiles'],
                                        figs['grids'])],
        'variants_note': variants_note(report),
        'sweeps': sweeps_context(report, figs['sweeps']),
        'has_plots': bool(report.doc.get('plots')),
        'lowpoly': lowpoly_context(report.lowpoly, figs['lowpoly'],
                                   report.out, report.src)
        if report.lowpoly else None,
        'filtering': filtering_context(report, figs),
        'interplay': interplay_context(report),
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
    with open(path + '.tmp', 'w', encoding='utf-8') as f:
        f.write(page.rstrip('\n') + '\n')  # one final newline
    os.replace(path + '.tmp', path)
    return path
