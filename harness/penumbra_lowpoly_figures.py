"""The matplotlib figures of a study's low-poly section.

figures/lowpoly-convergence-<group>.* (evaluator offsets vs
evaluator:analytic over the convergence axis), lowpoly-external-<group>.*
(other renderers vs their own analytic render) and lowpoly-shadow-<group>.*
(cast-shadow loss and shift, scenes with a cast shadow); a group is a scene
plus the values of any other axes. The data come from penumbra_data.LowPoly.
"""
import math

import matplotlib.ticker
import numpy as np

from penumbra_data import LP_PANELS, LP_SIDE, LP_TRUTH, REF, num, stem
from penumbra_plot import plt, save, worker_pool
from penumbra_style import method_colors

MARKERS = 'osD^vPX*<>p'
RENDERER_DASHES = ['-', (0, (5, 2)), (0, (6, 2, 1, 2)), (0, (2, 1.5))]


def log_floor(ax, values):
    """A log y axis when the positive values span more than a decade and
    none is negative; returns the floor where zeros are drawn (None: no
    zero, or a linear axis)."""
    v = values[np.isfinite(values)]
    pos = v[v > 0]
    if pos.size < 2 or (v < 0).any() or pos.max() / pos.min() < 20:
        return None
    ax.set_yscale('log')
    floor = 10.0 ** math.floor(math.log10(pos.min()) - 0.3)
    return floor if (v == 0).any() else None


def _panel(ax, lp, xs, ys, style):
    """One metric's lines; returns the floor its zeros are drawn on."""
    floor = log_floor(ax, np.concatenate(list(ys.values()) or [[]]))
    for i, (key, y) in enumerate(ys.items()):
        if floor is not None:
            y = np.where(y == 0, floor, y)
        # equal series overlap: later ones are drawn smaller and on top
        ax.plot(xs, y, label=style(key)[0], **style(key)[1], zorder=2 + i,
                marker=MARKERS[i % len(MARKERS)], mfc='none', mew=1.2,
                ms=max(3.0, 9 - 0.9 * i), lw=max(0.8, 2.6 - 0.3 * i))
    if floor is not None:
        ax.axhline(floor, color='0.55', lw=0.8, ls=':', zorder=1)
        ax.text(0.98, floor / 1.15, 'zero: drawn on this floor',
                fontsize=7, color='0.4', ha='right', va='top',
                transform=ax.get_yaxis_transform())
        ax.set_ylim(bottom=floor / 3)
    if lp.log2_levels():
        ax.set_xscale('log', base=2)
    ax.set_xticks(xs, [lp.level_text(t) for t in lp.levels],
                  rotation=45 if len(lp.levels) > 8 else 0)
    ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
    ax.grid(alpha=0.3)
    return floor


def lines_figure(name, title, lp, series, panels, style, figdir):
    """One panel per metric over the levels, one line per series; returns
    (paths, [(panel name, log y?, zeros on a floor?)])."""
    xs = np.array([num(t) for t in lp.levels]) if lp.numeric else \
        np.arange(len(lp.levels), dtype=float)
    # Tall enough for the legend beside the panels (a fifth of an inch per
    # line): a study with many offset values would otherwise squash them.
    fig, axs = plt.subplots(1, len(panels), squeeze=False,
                            layout='constrained',
                            figsize=(4.3 * len(panels) + 2.4,
                                     max(4.1, 1.2 + 0.2 * len(series))))
    floors = []
    for ax, (metric, pname, unit, scale) in zip(axs[0], panels):
        ys = {k: s[metric] * scale for k, s in series.items()}
        floor = _panel(ax, lp, xs, ys, style)
        floors.append((pname, ax.get_yscale() == 'log', floor is not None))
        ax.set(title=pname, xlabel=lp.xlabel, ylabel=f'{pname} ({unit})')
    axs[0][-1].legend(loc='upper left', bbox_to_anchor=(1.02, 1.0))
    fig.suptitle(title)
    return save(fig, figdir, name), floors


def line_style(lp, colors, own):
    """(label, line style) of a series: colour by offset, dashes by
    renderer for the external renderers."""
    def style(key):
        rend, off = key
        if not own:
            return off, dict(color=colors[off])
        ext = [r for r in lp.rend_ids if r != REF]
        dash = RENDERER_DASHES[ext.index(rend) % len(RENDERER_DASHES)] \
            if rend in ext else '-'
        return f'{rend}: {off}', dict(color=colors[off], ls=dash)
    return style


# What every drawing task shares, set before the pool forks: the workers
# inherit it instead of receiving the whole section with each task.
_SHARED = {}


def _draw_task(task):
    kind, group, title, series, panels, own = task
    lp, colors, figdir = _SHARED['lowpoly']
    return lines_figure(
        f'lowpoly-{kind}-{stem(group)}', f'{group}: {title}', lp, series,
        panels, line_style(lp, colors, own), figdir)


def lowpoly_figures(lp, figdir):
    """Every low-poly figure: per group the convergence and external
    figures, then per group with a cast shadow the shadow figure (drawn in
    worker processes, collected in that order). Returns
    {'convergence'|'external'|'shadow': {group: (PNG, floors)}, 'written':
    [every path]}, floors as lines_figure gives them."""
    figs = {'convergence': {}, 'external': {}, 'shadow': {}, 'written': []}
    tasks, shadow_groups = [], []
    for group in lp.groups:
        own, ext = lp.series(group, False), lp.series(group, True)
        if lp.cast_shadow_pixels(group):
            shadow_groups.append((group, own, ext))
        if own:
            tasks.append(('convergence', group,
                          f'{REF} offsets vs {REF}:{LP_TRUTH}', own,
                          LP_PANELS, False))
        if ext:
            tasks.append(('external', group,
                          'external renderers vs their own analytic render',
                          ext, LP_PANELS, True))
    for group, own, ext in shadow_groups:
        tasks.append(('shadow', group,
                      'cast-shadow side effects vs the analytic render',
                      {**own, **ext}, LP_SIDE[:2], bool(ext)))
    _SHARED['lowpoly'] = (lp, method_colors(lp.offsets), figdir)
    with worker_pool(len(tasks)) as pool:
        for task, (paths, floors) in zip(tasks, pool.imap(_draw_task, tasks)):
            kind, group = task[0], task[1]
            figs[kind][group] = (paths[0], floors)
            figs['written'].extend(paths)
    return figs
