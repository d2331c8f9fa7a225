"""The figures of the bump methods' ranking statistics (issue 37), each
built as a matplotlib Figure in a given style (penumbra_style) and saved by
the caller, so that the report (screen, PNG+SVG+PDF) and `report.py figure`
(one file, either style) draw them alike:

  ranking_fig     figures/ranking.*: the primary metric per method, a point
                  with its interval, on a linear axis; methods ordered by
                  rank group (penumbra_stats.ranked), groups banded and
                  labelled, the rule as the caption.
  statistics_fig  figures/statistics.*: the same overall and per scene.
  line_fig        figures/line-<axis>.*: a metric against one axis' levels
                  per method, with interval bars (numeric axes on a numeric
                  x, others categorical with short labels).
  mean_rmse_fig   figures/mean-rmse-terminator.*: the mean absolute
                  terminator RMSE (report.json `ranking`), labelled as the
                  different quantity it is.

Every value axis is in the unit of the matching metrics.csv column
(fractions, never percent) and its label says the unit.

Points far off the scale (a method several times worse than raw bump) would
squeeze the differences that matter (0.8 to 1.0 of raw bump's error) into a
sliver, so value axes end at the largest interval end within 1.3 x the upper
quartile of the ends, and a point beyond is drawn at the edge as a triangle
with its number and interval.
"""
import math
import textwrap

import numpy as np

from penumbra_data import METRICS, PRIMARY, fmt, metric_label, num, objs
from penumbra_plot import geometric, plt
from penumbra_stats import (
    depends, level_confidence, mean_of, numbered_key, ranked)

BAND = '0.93'                     # the shading of every other rank group


def wrapped(fig, text, points):
    """text broken into lines that fit the figure's width at `points`."""
    chars = max(30, int(fig.get_figwidth() * 72 / (0.55 * points)))
    return '\n'.join(textwrap.wrap(text, chars))


def value_label(metric, stats, width=40):
    """An axis label: the metric's name and its unit (the CSV column's),
    in lines of at most `width` characters."""
    if metric == PRIMARY:
        text = f'{stats.primary["name"]}, C ({METRICS[PRIMARY][1]})'
    else:
        text = metric_label(metric)
    name, _, unit = text.partition(' (')
    return name + '\n' + '\n'.join(textwrap.wrap('(' + unit, width))


def focus_limits(lo, hi, must=()):
    """(low, high) of a value axis: up to the largest interval end within
    1.3 x the upper quartile of the ends (values in `must` always inside);
    ends beyond are off the scale."""
    ends = [v for v in list(lo) + list(hi) + list(must) if math.isfinite(v)]
    if not ends:
        return 0.0, 1.0
    top = [v for v in list(hi) + list(must) if math.isfinite(v)]
    cap = 1.3 * max([np.percentile(top, 75)] + [v for v in must if
                                                math.isfinite(v)])
    high = max(v for v in top if v <= cap)
    low = min(ends)
    pad = 0.04 * (high - low if high > low else abs(high) or 1.0)
    # From 0 when the values are near it: a ratio's distance from 0 reads.
    lower = 0.0 if 0 <= low < 0.25 * high else low - pad
    return lower, high + pad


def interval_points(ax, rows, styles, lim, size=5):
    """Horizontal points with interval bars at y = rows' 'y'; a point past
    lim's upper end drawn at the edge (a triangle and its number)."""
    for r in rows:
        st = styles.get(r['method'], {'color': 'k', 'marker': 'o'})
        v, lo, hi = r['value'], r['lo'], r['hi']
        if not math.isfinite(v):
            ax.text(lim[0], r['y'], ' n/a', va='center', fontsize=7,
                    color='0.4')
            continue
        if v > lim[1]:
            ax.plot([lim[1]], [r['y']], marker='>', color=st['color'],
                    ms=size + 1, clip_on=False, ls='')
            ci = f' [{lo:#.3g}, {hi:#.3g}]' if math.isfinite(lo + hi) else ''
            ax.annotate(f'{v:#.3g}{ci}', (lim[1], r['y']),
                        xytext=(-2 * size, 0), textcoords='offset points',
                        ha='right', va='center', fontsize=7,
                        color=st['color'])
            continue
        err = [[max(v - lo, 0) if math.isfinite(lo) else 0],
               [max(hi - v, 0) if math.isfinite(hi) else 0]]
        ax.errorbar([v], [r['y']], xerr=err, color=st['color'],
                    marker=st['marker'] or 'o', ms=size, capsize=2,
                    ls='', elinewidth=1.0)
    ax.set_xlim(*lim)


def group_rows(rows, metric, stats, gap=0.6):
    """Ranked rows placed on y (top first) with a gap between groups:
    [{'method', 'group', 'y', 'value', 'lo', 'hi'}]."""
    out, y, last = [], 0.0, None
    for r in rows:
        if last is not None and r['group'] != last:
            y += gap
        v, lo, hi = mean_of(r['entry'], metric)
        out.append({'method': r['method'], 'group': r['group'],
                    'leader': r['leader'], 'y': y, 'value': v, 'lo': lo,
                    'hi': hi})
        last, y = r['group'], y + 1
    return out


def mark_groups(ax, placed):
    """Bands behind every other rank group and its label on the right."""
    groups = list(dict.fromkeys(p['group'] for p in placed))
    for k, g in enumerate(groups):
        ys = [p['y'] for p in placed if p['group'] == g]
        if k % 2 == 0:
            ax.axhspan(min(ys) - 0.5, max(ys) + 0.5, color=BAND, zorder=0,
                       lw=0)
        ax.text(1.035, (min(ys) + max(ys)) / 2,
                'no group' if g is None else f'group {g}',
                transform=ax.get_yaxis_transform(), va='center',
                fontsize=7, color='0.3')


def ranking_fig(stats, styles, style, methods=None, metric=PRIMARY):
    """The primary metric (or another `means` metric) per method with its
    interval, methods in rank-group order (a subset when `methods` is
    given), groups banded and labelled, the rule as the caption; None
    without a ranking."""
    rows = [r for r in stats.rows if methods is None or r['method'] in methods]
    if not rows:
        return None
    placed = group_rows(rows, metric, stats)
    span = placed[-1]['y'] + 1 if placed else 1
    fig, ax = plt.subplots(figsize=(style.width(6.4), 1.2 + 0.15 * span
                                    if style.paper else 1.5 + 0.24 * span),
                           layout='constrained')
    base = next((p['value'] for p in placed if p['method'] == 'none'),
                1.0 if metric == PRIMARY else math.nan)
    lim = focus_limits([p['lo'] for p in placed], [p['hi'] for p in placed],
                       [base])
    mark_groups(ax, placed)
    if math.isfinite(base):
        ax.axvline(base, color='0.3', lw=0.8, ls='--', zorder=1)
    interval_points(ax, placed, styles, lim)
    ax.set_yticks([p['y'] for p in placed], [p['method'] for p in placed])
    ax.set_ylim((placed[-1]['y'] if placed else 0) + 0.7, -0.7)
    ax.set_xlabel(value_label(metric, stats))
    ax.grid(axis='x', alpha=0.3)
    what = ('' if metric == PRIMARY else
            f'Not the ranking metric: ordered by the rank groups of '
            f'{stats.primary["name"]}. ')
    bars = stats.interval_text(metric)
    caption = (f'{what}Points: mean over {stats.overall.get("variants", "?")}'
               f' variants; bars: {bars}; dashed: raw bump (none). '
               f'{stats.rule}')
    fig.supxlabel(wrapped(fig, caption, 7), fontsize=7, ha='center')
    return fig


def statistics_fig(stats, styles, style):
    """The primary metric per method with its interval, overall and per
    scene, on panels of at most three columns (two on paper), methods in
    the overall rank-group order in every panel; None without statistics."""
    order = [r['method'] for r in stats.rows]
    if not order:
        return None
    panels = [('all variants', stats.overall)] + [
        (f'scene {name}', s) for name, s in stats.scenes if objs(s.get('methods'))]
    cols = min(2 if style.paper else 3, len(panels))
    nrows = -(-len(panels) // cols)
    fig, axes = plt.subplots(
        nrows, cols, sharey=True, squeeze=False, layout='constrained',
        figsize=(style.width(3.6 * cols + 1.6),
                 nrows * ((0.8 + 0.13 * len(order)) if style.paper else
                          (1.4 + 0.3 * len(order)))))
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    placed_all = []
    for title, s in panels:
        at = {r['method']: r for r in ranked(s)}
        placed = []
        for y, m in enumerate(order):
            v, lo, hi = mean_of(at[m]['entry'], PRIMARY) if m in at else \
                (math.nan,) * 3
            placed.append({'method': m, 'y': y, 'value': v, 'lo': lo,
                           'hi': hi})
        placed_all.append((title, s, placed))
    lim = focus_limits([p['lo'] for *_, pl in placed_all for p in pl],
                       [p['hi'] for *_, pl in placed_all for p in pl], [1.0])
    for ax, (title, s, placed) in zip(axes.flat, placed_all):
        ax.axvline(1.0, color='0.3', lw=0.8, ls='--')
        interval_points(ax, placed, styles, lim, size=4)
        ax.set_title(f'{title} ({s.get("variants", "?")} variants)',
                     fontsize=8 if style.paper else 9)
        ax.grid(axis='x', alpha=0.3)
    for k, ax in enumerate(axes.flat[:len(panels)]):
        if k + cols >= len(panels):  # no panel below it
            ax.set_xlabel(value_label(PRIMARY, stats), fontsize=8)
    axes[0][0].set_yticks(range(len(order)), order)
    axes[0][0].set_ylim(len(order) - 0.5, -0.5)
    fig.supxlabel(wrapped(fig, f'Bars: {stats.interval_text()}; dashed: raw '
                          'bump (C = 1); methods in the overall rank-group '
                          'order in every panel.', 7), fontsize=7)
    return fig


def line_positions(axis, n_methods):
    """(x of each level, dodge(k) -> x of method k's points, log x?)."""
    levels = axis['levels']
    if axis['numeric']:
        xs = np.array([num(lv['value']) for lv in levels])
        log = geometric(xs)
        span = (np.log(xs.max() / xs.min()) if log else xs.max() - xs.min()) \
            if xs.size > 1 and xs.min() > 0 else 1.0
        step = 0.02 * span

        def dodge(k):
            d = (k - (n_methods - 1) / 2) * step
            return xs * math.exp(d) if log else xs + d
        return xs, dodge, log
    xs = np.arange(len(levels), dtype=float)
    return xs, (lambda k: xs + (k - (n_methods - 1) / 2) *
                min(0.08, 0.6 / max(n_methods, 1))), False


def line_series(axis, metric, method):
    """(mean, lo, hi) arrays over the axis' levels of one method."""
    vals = []
    for lv in axis['levels']:
        e = next((x for x in objs(lv['ranking'].get('methods'))
                  if str(x.get('method')) == method), None)
        vals.append(mean_of(e, metric) if e else (math.nan,) * 3)
    return np.array(vals, dtype=float).T.reshape(3, -1)


def line_fig(stats, axis, metric, methods, styles, style):
    """A metric against one axis' levels, a line per method with interval
    bars (dodged sideways so that they do not cover each other); None
    when no method has a value (a study without raw bump has no C)."""
    if not any(np.isfinite(line_series(axis, metric, m)[0]).any()
               for m in methods):
        return None
    narrow = style.paper and style.columns == 1
    fig, ax = plt.subplots(figsize=(style.width(6.4), 3.9 if narrow else
                                    3.4 if style.paper else 4.2),
                           layout='constrained')
    xs, dodge, log = line_positions(axis, len(methods))
    marked = {m: i for m, i in depends(axis).items() if m in methods}
    for k, m in enumerate(methods):
        y, lo, hi = line_series(axis, metric, m)
        st = styles.get(m, {'color': 'k', 'ls': '-', 'marker': 'o'})
        err = np.array([np.nan_to_num(y - lo), np.nan_to_num(hi - y)])
        ax.errorbar(dodge(k), y, yerr=np.clip(err, 0, None),
                    color=st['color'], ls=st['ls'], marker=st['marker'] or 'o',
                    capsize=2, lw=1.2, ms=4,
                    label=m + (' †' if m in marked else ''))
    if metric == PRIMARY:
        ax.axhline(1.0, color='0.3', lw=0.8, ls=':', zorder=0)
    if log:
        ax.set_xscale('log')
        ax.minorticks_off()
    ids = [lv['id'] for lv in axis['levels']]
    ax.set_xticks(xs, ids)
    if not axis['numeric'] and max(map(len, ids), default=0) > 10:
        plt.setp(ax.get_xticklabels(), rotation=20, ha='right')
    pad = 0.5 if not axis['numeric'] else 0
    if pad:
        ax.set_xlim(-pad, len(xs) - 1 + pad)
    ax.set_xlabel(axis['label'])
    ax.set_ylabel(value_label(metric, stats, 30 if narrow else 40))
    ax.grid(alpha=0.3)
    ncol = 2 if narrow else 3
    if style.paper:
        ax.legend(loc='upper center', bbox_to_anchor=(0.5, -0.2 if narrow
                                                      else -0.16),
                  ncol=ncol, frameon=False)
    else:
        ax.legend(loc='upper left', bbox_to_anchor=(1.01, 1), title='method')
    fig.supxlabel(wrapped(fig, line_caption(stats, axis, metric, marked), 7),
                  fontsize=7)
    return fig


def line_caption(stats, axis, metric, marked):
    """What the points and bars of a line figure are."""
    n = [lv['ranking'].get('variants', '?') for lv in axis['levels']]
    parts = [f'Points: mean over each level\'s variants ({", ".join(map(str, n))})'
             f'; bars: {stats.interval_text(metric, level_confidence(axis))}'
             + ('; dotted: raw bump (C = 1)' if metric == PRIMARY else '')]
    if marked:
        parts.append('†: the effect depends on the level (interaction, '
                     'Holm-adjusted p ' + ', '.join(
                         f'{m} {fmt(i.get("p_holm"), digits=2)}'
                         for m, i in marked.items()) + ')')
    if axis.get('computed'):
        parts.append('Computed by the harness from the comparisons '
                     '(this report.json has no statistics.by_axis)')
    if numbered_key(axis['levels']):
        parts.append('Levels: ' + numbered_key(axis['levels']))
    return '. '.join(parts) + '.'


def mean_rmse_fig(stats, styles, style):
    """The mean absolute terminator RMSE per method over variants (report.
    json `ranking`'s metric; a different quantity from the ranking
    metric), lowest first, with its 95 % interval where statistics'
    `means` give one; None when there is none."""
    rk = stats.report.ranking
    metric = str(rk.get('metric', 'profile.rmse_terminator'))
    rows = [(r['method'],) + mean_of(r['entry'], metric) for r in stats.rows]
    rows = [x for x in rows if math.isfinite(x[1])]
    with_ci = bool(rows)
    rows = rows or [(str(e.get('method')), num(e.get('mean')), math.nan,
                     math.nan) for e in objs(rk.get('overall'))]
    if not rows:
        return None
    rows.sort(key=lambda x: (not math.isfinite(x[1]), x[1]
                             if math.isfinite(x[1]) else 0))
    placed = [{'method': m, 'y': y, 'value': v, 'lo': lo, 'hi': hi}
              for y, (m, v, lo, hi) in enumerate(rows)]
    fig, ax = plt.subplots(figsize=(style.width(6.4), (1.3 if style.paper
                                                       else 1.6) +
                                    (0.15 if style.paper else 0.24) *
                                    len(rows)), layout='constrained')
    base = next((p['value'] for p in placed if p['method'] == 'none'),
                math.nan)
    lim = focus_limits([p['lo'] if with_ci else p['value'] for p in placed],
                       [p['hi'] if with_ci else p['value'] for p in placed],
                       [base, 0.0])
    if math.isfinite(base):
        ax.axvline(base, color='0.3', lw=0.8, ls='--', zorder=1)
    interval_points(ax, placed, styles, lim)
    ax.set_yticks([p['y'] for p in placed], [p['method'] for p in placed])
    ax.set_ylim(len(placed) - 0.5, -0.5)
    ax.grid(axis='x', alpha=0.3)
    ax.set_xlabel(('mean absolute ' + metric_label(metric)).replace(
        ' (', '\n(', 1))
    bars = ('bars: 95 % bootstrap interval over variants' if with_ci else
            'this report.json gives no interval for it')
    fig.supxlabel(wrapped(fig, 'Mean over variants of the absolute error '
                          f'({rk.get("renderer", "?")} against '
                          f'{rk.get("reference", "?")}); {bars}; dashed: '
                          'raw bump. NOT the ranking metric: the variants '
                          'with the largest errors (the largest '
                          'amplitudes) weigh most (see statistics.notes).',
                          7), fontsize=7)
    return fig
