"""The top of report.html: provenance, notices, the headline (statistics.
headline, then the rank-group table), the ranking, statistics and line
figures with where each method helps and hurts, the mean absolute RMSE
table labelled as the different quantity it is, and which variants have a
section of their own.

Plain context (penumbra_context's tables and figures); every string from
report.json goes to the template unescaped here and is escaped there.
"""
import urllib.parse

from penumbra_context import figure_file
from penumbra_data import REF, axis_index, fmt, obj, objs, stem
from penumbra_stats import depends, flips, line_methods, short_ids
from penumbra_tables import (
    formatted, heading, level_table, numeric_column, ranking_table,
    table_caption)


def html_table(t):
    """A penumbra_tables table as the template's table (numbers as text
    with their column's decimals, right-aligned)."""
    head = [heading(h, u) for h, u, _ in t['head']]
    num_cols = [numeric_column(t, k) for k in range(len(head))]
    rows = [[{'text': c, 'cls': ('n na' if c == 'n/a' else 'n')
              if num_cols[k] else ''} for k, c in enumerate(r)]
            for r in formatted(t)]
    return {'head': head, 'rows': rows, 'row_class': ''}


def provenance_context(doc):
    """[(what, value)] of report.json's provenance, or None when absent."""
    p = doc.get('provenance')
    if not isinstance(p, dict):
        return None
    m, r = obj(p.get('machine')), obj(p.get('renderers'))
    dirty = {True: ' (with uncommitted changes)', False: ''}.get(
        p.get('dirty'), '')
    rows = [('penumbra', str(p.get('penumbra', '?'))),
            ('commit', str(p.get('commit', '?')) + dirty),
            ('written (UTC)', str(p.get('date', '?'))),
            ('machine', ', '.join(str(x) for x in (
                m.get('cpu'), f'{m.get("cores")} cores' if m.get('cores')
                else None, m.get('system')) if x)),
            ('renderers', ', '.join(f'{k} {v}' for k, v in r.items())),
            ('study file SHA-256', str(p.get('study_sha256', '?')))]
    return [{'what': k, 'value': v} for k, v in rows]


def headline_context(report, stats):
    """The lead sentences, the rank-group table with the rule, or why there
    is no ranking."""
    if not report.variants:
        return {'skipped': None, 'sentences': [], 'table': None}
    if not stats.present or not stats.rows:
        return {'skipped': 'No ranking: this report.json has no ranking '
                'statistics. A ranking needs raw bump (`none`), the '
                'baseline the primary metric is relative to; a study that '
                'names no `none` is ranked only when the run adds it (see '
                'the notices above, if any).'}
    t = ranking_table(stats)
    return {'skipped': None, 'sentences': stats.headline,
            'primary': stats.primary, 'rule': stats.rule,
            'table': html_table(t), 'caption': table_caption(stats, t),
            'definition': str(obj(report.doc.get('statistics')).get(
                'definition', ''))}


def interaction_sentence(axis, i):
    """'chiang2019 depends on amplitude A (Holm-adjusted p = 0.002):
    helps at 0.02 (C 0.55 [0.50, 0.60]), hurts at 0.005 (...).'"""
    parts = []
    for lv in objs(i.get('levels')):
        ci = lv.get('combined_ci')
        ends = ci if isinstance(ci, list) and len(ci) == 2 else [None, None]
        at = lv.get('value_id', lv.get('value_label'))
        parts.append(f'{lv.get("verdict", "?")} at {at} (C '
                     f'{fmt(lv.get("combined"))} [{fmt(ends[0])}, '
                     f'{fmt(ends[1])}])')
    return (f'{i.get("method")}: its effect depends on {axis["label"]} '
            f'(interaction, Holm-adjusted p = {fmt(i.get("p_holm"), digits=2)})'
            + (': ' + '; '.join(parts) if parts else '') + '.')


def axis_findings(axis):
    """A sentence per method that helps at one level and hurts at
    another, then one naming the others whose effect depends on the
    level."""
    turn = flips(axis)
    rest = [m for m in depends(axis) if m not in turn]
    out = [interaction_sentence(axis, i) for i in turn.values()]
    if rest:
        out.append(f'Also depends on {axis["label"]} (Holm-adjusted p < '
                   '0.05), without turning from help to harm: ' +
                   ', '.join(rest) + '.')
    return out


def lines_context(report, stats, figs):
    """Per axis: its line figure, the interactions in sentences and the
    per-level table (rank group in each level)."""
    out = []
    for axis, png in figs.get('lines', []):
        if axis is None:
            continue
        t = level_table(stats, axis)
        name = 'figures/line-' + stem(axis['pointer'].strip('/').replace(
            '/', '-'))
        shown = ', '.join(line_methods(figs['shown'], axis))
        out.append({
            'title': axis['label'], 'pointer': axis['pointer'],
            'figure': figure_file(
                png, f'error against {axis["label"]}',
                f'{name}.{{png,svg,pdf}}: combined error C against '
                f'{axis["label"]} for the highlighted methods and those '
                f'that help at one level and hurt at another ({shown}); '
                'redraw any subset with report.py figure OUT --kind line '
                f'--x {axis["pointer"]} --methods a,b,c.') if png else None,
            'findings': axis_findings(axis),
            'table': html_table(t), 'caption': table_caption(stats, t)})
    return out


def mean_rmse_context(report, stats, figs, tables):
    """The old 'Mean profile.rmse_terminator' block, labelled as a
    different quantity, with statistics.notes beside it."""
    if not tables and not figs.get('mean_rmse'):
        return None
    return {'tables': tables, 'notes': stats.notes,
            'figure': figure_file(figs['mean_rmse'], 'mean absolute RMSE',
                                  'figures/mean-rmse-terminator.{png,svg,pdf}'
                                  ': the mean absolute terminator RMSE; not '
                                  'the ranking metric')
            if figs.get('mean_rmse') else None}


def level_counts(report, shown):
    """'amplitude A: 0.005 ×16, 0.01 ×16, 0.02 ×16; ...' of the shown
    variants (scenes first)."""
    parts = []
    scenes = {}
    for v in shown:
        scenes[str(v.get('scene'))] = scenes.get(str(v.get('scene')), 0) + 1
    parts.append('scene: ' + ', '.join(f'{k} ×{n}' for k, n in scenes.items()))
    for k, axis in enumerate(objs(report.doc.get('axes'))):
        labels = short_ids(axis)
        counts = [0] * len(labels)
        for v in shown:
            av = v.get('axis_values')
            i = value_index(axis, av[k] if isinstance(av, list) and
                            len(av) > k else None)
            if i is not None:
                counts[i] += 1
        parts.append(f'{axis.get("label", axis.get("pointer"))}: ' + ', '.join(
            f'{t} ×{n}' for t, n in zip(labels, counts)))
    return '; '.join(parts)


def value_index(axis, v):
    vals = axis.get('values') if isinstance(axis.get('values'), list) else []
    return None if v is None else axis_index(vals, v)


def variants_context(report):
    """Which variants have a section and why, and the rest: a table of
    their ids, labels and links to their evaluator images."""
    n, shown = len(report.variants), report.shown
    if len(shown) == n:
        return {'note': None, 'rest': []}
    ids = {id(v) for v in shown}
    rest = [v for v in report.variants if id(v) not in ids]
    note = (f'{n} variants: the {len(shown)} sections below show a balanced '
            f'pick of them (a page of {n} sections does not read), so that every '
            'scene and every value of every axis appears about equally often: '
            'each pick is the variant whose scene and axis values have appeared '
            'least so far (on a tie, the first of the variants evenly spaced '
            'over the study\'s order). '
            f'Shown: {level_counts(report, shown)}. The other {len(rest)} are '
            'listed after the sections, with links to their images; every '
            'variant\'s numbers are in metrics.csv and report.json, and the '
            'ranking, statistics, line figures and sweeps use them all.')
    return {'note': note, 'rest': [
        {'id': str(v.get('id')), 'label': str(v.get('label', '')),
         'links': [{'href': urllib.parse.quote(r['image']),
                    'text': str(r.get('method')) if r.get('representation')
                    == 'bump' else str(r.get('representation'))}
                   for r in objs(v.get('renders'))
                   if r.get('renderer') == REF and
                   isinstance(r.get('image'), str)]} for v in rest]}
