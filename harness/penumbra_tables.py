"""The ranking tables of a study, for the page and for papers
(`report.py table`): one builder per table, three writers.

  ranking_table(stats)       rank group, method, the primary metric C with
                             its interval, C minus the group leader's,
                             terminator error removed, grazing-view
                             difference from raw bump, verdict vs raw bump;
  level_table(stats, axis)   methods x the axis' levels, each cell the mean
                             C with its interval and the method's rank group
                             in that level.
  markdown(), latex(), csv_text()  write either.

Rank groups come from penumbra_stats.ranked (the one reading every figure
and the page use). Numbers are fractions, as in report.json and metrics.csv
(the headings say of what). Digits: per column, enough decimals that the
median interval's width shows two significant digits (at most 4), so a
column's numbers line up and no digit claims much more than the intervals
support. The CSV writes every number in full (shortest round-trip form)
for analysis. LaTeX uses booktabs and escapes every string.
"""
import csv
import io
import math

from penumbra_data import FRACTION, PRIMARY, num
from penumbra_stats import (
    level_confidence, mean_of, metric_unit, pair, ranked)

RATIO = "fraction of raw bump's"


def fixed(x, d):
    """x with d decimals, never '-0.00'."""
    t = f'{x:.{d}f}'
    return t[1:] if t.startswith('-') and not t.strip('-0.') else t


class Num:
    """A table number: value with an optional interval (lo, hi)."""

    def __init__(self, value, ci=None, label=None):
        self.value = num(value)
        self.ci = tuple(ci) if ci is not None else None
        self.label = label  # shown instead of the number (e.g. 'leader')

    def width(self):
        lo, hi = self.ci or (math.nan, math.nan)
        return hi - lo if math.isfinite(lo) and math.isfinite(hi) else math.nan

    def text(self, d):
        if self.label is not None:
            return self.label
        if not math.isfinite(self.value):
            return 'n/a'
        t = fixed(self.value, d)
        if self.ci is not None and all(math.isfinite(v) for v in self.ci):
            t += f' [{fixed(self.ci[0], d)}, {fixed(self.ci[1], d)}]'
        return t


def decimals(cells):
    """Decimals of a column: two significant digits of its median interval
    width (of its median non-zero magnitude without intervals), at most 4:
    the typical interval, not the narrowest (raw bump's own is 0 wide)."""
    widths = [c.width() for c in cells if isinstance(c, Num)]
    widths = [w for w in widths if math.isfinite(w) and w > 0]
    if not widths:
        widths = [abs(c.value) for c in cells if isinstance(c, Num) and
                  math.isfinite(c.value) and c.value != 0]
    if not widths:
        return 2
    typical = sorted(widths)[len(widths) // 2]
    return min(4, max(0, 1 - math.floor(math.log10(typical))))


def verdict(entry):
    """Better, worse or tied with raw bump: C's interval below 1, above 1,
    or containing it (a difference inside its interval is a tie)."""
    if str(entry.get('method')) == 'none':
        return 'baseline'
    lo, hi = pair(entry.get('combined_ci'))
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return 'n/a'
    return 'better' if hi < 1 else 'worse' if lo > 1 else 'tie'


# (heading, unit, CSV column)
RANKING_HEAD = [
    ('rank group', '', 'rank_group'), ('method', '', 'method'),
    ('combined error C', RATIO + ' E_term + E_view; 1 = raw bump', PRIMARY),
    ("C minus its group leader's", RATIO, 'versus_leader'),
    ('terminator error removed', RATIO + ' E_term', 'terminator_improvement'),
    ('grazing-view RMSE minus raw bump', FRACTION, 'view_vs_none'),
    ('vs raw bump', '', 'verdict')]


def heading(name, unit):
    return f'{name} ({unit})' if unit else name


def ranking_table(stats, rs=None):
    """The rank-group table of a RankingStats (overall when None):
    {'head': [(heading, unit, csv column)], 'rows': [[cell]], 'groups':
    [group per row]}."""
    rows, groups = [], []
    for r in ranked(stats.overall if rs is None else rs):
        e, v = r['entry'], r['versus']
        view = e.get('view_vs_none') if isinstance(e.get('view_vs_none'),
                                                   dict) else {}
        c, lo, hi = mean_of(e, PRIMARY)
        rows.append([
            r['group'] if r['group'] is not None else '–', r['method'],
            Num(c, (lo, hi)),
            Num(math.nan, label='leader') if r['leader'] == r['method'] else
            Num(v.get('mean_difference'), pair(v.get('ci'))) if v else
            Num(math.nan),
            Num(e.get('terminator_improvement'),
                pair(e.get('terminator_improvement_ci'))),
            Num(view.get('mean_difference'), pair(view.get('ci'))),
            verdict(e)])
        groups.append(r['group'])
    return {'head': RANKING_HEAD, 'rows': rows, 'groups': groups}


def level_table(stats, axis, metric=PRIMARY):
    """Methods x the axis' levels: a row per method (the overall rank
    order), each cell (Num, rank group in that level); same keys as
    ranking_table, plus 'levels'."""
    levels = axis['levels']
    cells = {}
    for j, lv in enumerate(levels):
        for r in ranked(lv['ranking']):
            mean, lo, hi = mean_of(r['entry'], metric)
            cells[(r['method'], j)] = (Num(mean, (lo, hi)), r['group'])
    order = list(dict.fromkeys(
        [m for m in stats.methods if any((m, j) in cells
                                         for j in range(len(levels)))] +
        [m for m, _ in cells]))
    rows = [[m] + [cells.get((m, j), (Num(math.nan), None))
                   for j in range(len(levels))] for m in order]
    unit = metric_unit(metric)
    head = [('method', '', 'method')] + [
        (f'{axis["label"]} = {lv["id"]}', '', lv['id']) for lv in levels]
    return {'head': head, 'rows': rows, 'groups': None, 'levels': levels,
            'unit': unit, 'metric': metric, 'axis': axis}


def formatted(table):
    """Every cell as text, each column's numbers with its decimals; a
    (Num, group) cell of a level table as 'v [lo, hi] (g1)'."""
    rows = table['rows']
    digits = [decimals([c[0] if isinstance(c, tuple) else c
                        for c in (row[k] for row in rows)])
              for k in range(len(table['head']))]
    if 'levels' in table:  # one quantity in every level's column
        digits[1:] = [decimals([c[0] for row in rows for c in row[1:]])] * \
            (len(digits) - 1)
    out = []
    for row in rows:
        line = []
        for k, c in enumerate(row):
            n, g = c if isinstance(c, tuple) else (c, None)
            t = n.text(digits[k]) if isinstance(n, Num) else str(n)
            if g is not None and math.isfinite(n.value):
                t += f' (g{g})'
            line.append(t)
        out.append(line)
    return out


def numeric_column(table, k):
    return all(isinstance(r[k], (Num, tuple, int)) for r in table['rows'])


def markdown(table, caption):
    """A pipe table, numbers right-aligned, the caption below."""
    def esc(s):
        return str(s).replace('|', '\\|')
    head = [heading(h, u) for h, u, _ in table['head']]
    lines = ['| ' + ' | '.join(map(esc, head)) + ' |',
             '|' + '|'.join('---:' if numeric_column(table, k) else '---'
                            for k in range(len(head))) + '|']
    lines += ['| ' + ' | '.join(map(esc, r)) + ' |'
              for r in formatted(table)]
    return '\n'.join(lines) + '\n\n' + caption + '\n'


LATEX_SPECIAL = {'\\': r'\textbackslash{}', '&': r'\&', '%': r'\%',
                 '$': r'\$', '#': r'\#', '_': r'\_', '{': r'\{', '}': r'\}',
                 '~': r'\textasciitilde{}', '^': r'\textasciicircum{}',
                 '<': r'\textless{}', '>': r'\textgreater{}',
                 '·': r'$\cdot$', 'π': r'$\pi$', '°': r'$^\circ$',
                 '−': '--', '–': '--', '’': "'", '×': r'$\times$',
                 '±': r'$\pm$'}


def tex(s):
    """A string as LaTeX text: specials escaped, other non-ASCII as '?'
    (pdflatex's default input fails on what it does not know)."""
    return ''.join(LATEX_SPECIAL.get(c, c if c.isascii() else '?')
                   for c in str(s))


# The ranking table's head in LaTeX: short symbols over their units (the
# caption defines them); a paper column has no room for the page's headings.
RANKING_TEX = [
    ['Group', 'Method', '$C$', r'$C - C_\mathrm{leader}$',
     r'$1 - E_\mathrm{term}/E_\mathrm{term}^\mathrm{none}$',
     r'$E_\mathrm{view} - E_\mathrm{view}^\mathrm{none}$', r'vs.\ none'],
    ['', '', '(ratio)', '(ratio)', '(ratio)', r'(albedo$\cdot E/\pi$)', '']]


def latex_head(table):
    """The head rows of a table in LaTeX: the ranking table's symbols, or
    a level table's axis over its levels' ids."""
    if 'levels' not in table:
        return [' & '.join(r) + r' \\' for r in RANKING_TEX]
    n = len(table['levels'])
    unit = '$C$, ratio' if table['metric'] == PRIMARY else tex(table['unit'])
    return [f'Method & \\multicolumn{{{n}}}{{c}}{{{tex(table["axis"]["label"])}'
            f' ({unit})}}' + r' \\',
            f'\\cmidrule(lr){{2-{n + 1}}}',
            ' & '.join([''] + [tex(lv['id']) for lv in table['levels']]) +
            r' \\']


def latex(table, caption):
    """A booktabs table environment (\\usepackage{booktabs}); a rule
    between rank groups."""
    cols = ''.join('r' if numeric_column(table, k) else 'l'
                   for k in range(len(table['head'])))
    lines = ['% needs \\usepackage{booktabs}',
             '\\begin{table}[tbp]', '\\centering', '\\small',
             f'\\begin{{tabular}}{{{cols}}}', '\\toprule'] + \
        latex_head(table) + ['\\midrule']
    groups = table.get('groups')
    for k, r in enumerate(formatted(table)):
        if groups and k and groups[k] != groups[k - 1]:
            lines.append('\\midrule')
        lines.append(' & '.join(tex(c) for c in r) + r' \\')
    lines += ['\\bottomrule', '\\end{tabular}',
              f'\\caption{{{tex(caption)}}}', '\\end{table}']
    return '\n'.join(lines) + '\n'


def csv_text(table):
    """CSV (RFC 4180), every number in full (shortest round-trip form):
    the ranking table a row per method, a number as three columns
    (NAME, NAME_ci_low, NAME_ci_high); a level table in long form, a row
    per method and level."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator='\n')
    if 'levels' in table:
        w.writerow(['axis', 'level', 'level_label', 'method', 'metric',
                    'value', 'ci_low', 'ci_high', 'rank_group', 'unit'])
        for row in table['rows']:
            for lv, (n, g) in zip(table['levels'], row[1:]):
                lo, hi = n.ci or (math.nan, math.nan)
                w.writerow([table['axis']['pointer'], lv['id'], lv['label'],
                            row[0], table['metric'], full(n.value), full(lo),
                            full(hi), '' if g is None else g, table['unit']])
        return out.getvalue()
    header = []
    for (_, _, key), c in zip(table['head'], table['rows'][0] if
                              table['rows'] else []):
        header += [key, key + '_ci_low', key + '_ci_high'] \
            if isinstance(c, Num) else [key]
    w.writerow(header or [k for _, _, k in table['head']])
    for row in table['rows']:
        line = []
        for c in row:
            line += [full(c.value), full(c.ci[0] if c.ci else math.nan),
                     full(c.ci[1] if c.ci else math.nan)] \
                if isinstance(c, Num) else [c]
        w.writerow(line)
    return out.getvalue()


def full(x):
    """A number in its shortest round-trip form; empty when undefined."""
    return repr(float(x)) if math.isfinite(num(x)) else ''


def table_caption(stats, table):
    """What the table's numbers are, with the rank rule."""
    if 'levels' in table:
        axis = table['axis']
        bars = stats.interval_text(table['metric'], level_confidence(axis))
        what = (f'{table["metric"]} per level of {axis["label"]} '
                f'({table["unit"]}): mean over the level\'s variants '
                f'[{bars}]; (gN): the method\'s rank group in that level')
        if axis.get('computed'):
            what += ' (none: this report.json has no statistics.by_axis)'
    else:
        what = (f'C: {stats.primary["name"]} ({stats.primary["unit"]}), '
                f'mean over {stats.overall.get("variants", "?")} variants '
                f'[{stats.interval_text()}]; C - C_leader: the paired '
                'difference from its rank group\'s leader; 1 - E_term/'
                'E_term(none): the share of raw bump\'s terminator error '
                'removed; E_view - E_view(none): the grazing-view RMSE added '
                f'({FRACTION}); the others with 95 % intervals; a difference '
                'whose interval contains 0 is a tie')
    return f'{what}. {stats.rule}'
