"""Sweeps: a metric over two study axes (report.json plots[]), the mean over
the other axes, as an annotated heatmap or a contour plot.

Every panel has its own colour scale and colour bar: one scale shared by
all methods let the worst method (shading-offset's 16.9) flatten every
other panel to one colour. Cell labels are 8 pt. Values are in the metric's
metrics.csv unit (fractions of albedo·E/π, never percent), which the colour
bar's label states.

  sweep_figures   the report's: per scene, plot-<k>-<scene>.* (small
                  multiples, one panel per method) and
                  plot-<k>-<scene>-<metric>-<method>.* (one method).
  heatmap_fig     `report.py figure --kind heatmap`: one figure of the
                  chosen methods, one scene or all scenes pooled.
"""
import math

import numpy as np
from matplotlib.ticker import MaxNLocator

from penumbra_data import (
    REF, BadInput, axis_index, axis_labels, fmt, get_metric, metric_label,
    num, obj, objs, stem)
from penumbra_plot import (
    contour_lines, fitted_title, geometric, plt, save, worker_pool)
from penumbra_style import SCREEN

CELL_PT = 8                       # heatmap cell labels, every style


def grid_lim(grid):
    """(vmin, vmax) of one panel's colour scale: its finite values' range,
    widened to at least 10 % of its largest magnitude, so that a panel of
    near-equal values (0.0519 and 0.0520) does not span the whole map and
    read as a strong effect."""
    v = grid[np.isfinite(grid)]
    if not v.size:
        return 0.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    pad = max(0.0, 0.1 * max(abs(lo), abs(hi), 1e-9) - (hi - lo)) / 2
    return lo - pad, hi + pad


def _draw_contour(ax, grid, xs, ys, ticks, cmap, norm):
    xt, yt = ticks
    X, Y = np.meshgrid([num(v) for v in xs], [num(v) for v in ys])
    z = np.ma.masked_invalid(grid)
    levels = MaxNLocator(10).tick_values(norm.vmin, norm.vmax)
    im = ax.contourf(X, Y, z, levels=levels, cmap=cmap, norm=norm)
    contour_lines(ax, X, Y, z, levels, '%.3g')
    ax.plot(X.ravel(), Y.ravel(), 'o', color='w', ms=3.5, mec='k',
            mew=0.6, label='study samples')
    ax.legend(loc='upper right', fontsize=7)
    for v, set_scale in ((xs, ax.set_xscale), (ys, ax.set_yscale)):
        if geometric([num(t) for t in v]):
            set_scale('log')
    ax.minorticks_off()
    ax.set_xticks(X[0], xt, rotation=45, ha='right')
    ax.set_yticks(Y[:, 0], yt)
    return im


def draw_grid(ax, grid, xs, ys, labels, kind, title):
    """One panel on its own colour scale: contour when kind == 'contour',
    else annotated heatmap; labels: (x label, y label, x tick texts,
    y tick texts)."""
    cmap, norm = plt.get_cmap('viridis'), plt.Normalize(*grid_lim(grid))
    if kind == 'contour':
        im = _draw_contour(ax, grid, xs, ys, labels[2:], cmap, norm)
    else:
        im = ax.imshow(grid, origin='lower', cmap=cmap, norm=norm,
                       aspect='auto')
        for (i, j), v in np.ndenumerate(grid):
            lum = np.dot(cmap(norm(v))[:3], [0.299, 0.587, 0.114])
            ax.text(j, i, fmt(v), ha='center', va='center', fontsize=CELL_PT,
                    color='w' if lum < 0.5 and math.isfinite(v) else 'k')
        ax.set_xticks(range(len(xs)), labels[2], rotation=30, ha='right')
        ax.set_yticks(range(len(ys)), labels[3])
    ax.set(xlabel=labels[0], ylabel=labels[1], title=title)
    return im


def sweep_cells(doc, axes, x, y, metric, rend):
    """{(scene, method): [sum grid, count grid]} of the comparisons of
    renderer rend against its displacement, over axes[y] x axes[x]."""
    xs, ys = axes[x]['values'], axes[y]['values']
    variants = {v.get('id'): v for v in objs(doc.get('variants'))}
    cells = {}
    for c in objs(doc.get('comparisons')):
        var, val = obj(variants.get(c.get('variant'))), get_metric(c, metric)
        av = var.get('axis_values')
        if c.get('renderer') != rend or not math.isfinite(val) or \
                c.get('reference') != f'{rend}:displacement' or \
                not isinstance(av, list) or len(av) != len(axes):
            continue
        i, j = axis_index(ys, av[y]), axis_index(xs, av[x])
        if i is not None and j is not None:
            key = (str(c.get('scene', var.get('scene'))),
                   str(c.get('method')))
            acc = cells.setdefault(key, np.zeros((2, len(ys), len(xs))))
            acc[:, i, j] += (val, 1)
    return cells


def sweep_layout(doc, src, k, plot):
    """The checked axes of plots[k]: (x, y, xs, ys, labels, numeric, ox,
    oy), values sorted when both axes are numeric; labels: (x label, y
    label, x tick texts, y tick texts)."""
    axes = objs(doc.get('axes'))
    x, y = plot.get('x'), plot.get('y')
    if x == y or not all(type(i) is int and 0 <= i < len(axes)
                         for i in (x, y)):
        raise BadInput(src, f'plots[{k}]: x and y must be two different '
                       f'indices into axes (0..{len(axes) - 1}), got {x!r}, '
                       f'{y!r}')
    xs, ys = axes[x]['values'], axes[y]['values']
    numeric = all(len(v) >= 2 and all(math.isfinite(num(t)) for t in v)
                  for v in (xs, ys))
    ox, oy = (np.argsort([num(t) for t in v]) if numeric
              else np.arange(len(v)) for v in (xs, ys))
    xt, yt = ([axis_labels(axes[a])[i].replace(', ', ',\n')
               for i in o] for a, o in ((x, ox), (y, oy)))
    labels = [str(axes[i].get('label', axes[i].get('pointer')))
              for i in (x, y)] + [xt, yt]
    return (x, y, [xs[i] for i in ox], [ys[i] for i in oy], labels, numeric,
            ox, oy)


def grid_kind(plot, numeric, grids):
    return 'contour' if plot.get('kind', 'contour') == 'contour' and \
        numeric and all(np.isfinite(g).sum() >= 4
                        for g in grids.values()) else 'heatmap'


def panels_fig(grids, layout, kind, metric, note, style=SCREEN):
    """Small multiples, one panel and colour bar per method (own scale)."""
    xs, ys, labels = layout
    cols = min(len(grids), 2 if style.paper else 3)
    rows = -(-len(grids) // cols)
    pw = 3.3 if style.paper and style.columns == 2 else 4.6
    fig, axs = plt.subplots(rows, cols, squeeze=False, layout='constrained',
                            figsize=(style.width(pw * cols + 0.6),
                                     (2.6 if style.paper else 4.2) * rows
                                     + 0.5))
    for a in axs.flat[len(grids):]:
        a.set_visible(False)
    unit = '(' + metric_label(metric).partition(' (')[2]
    for k, (a, (m, g)) in enumerate(zip(axs.flat, grids.items())):
        fig.colorbar(draw_grid(a, g, xs, ys, labels, kind, m), ax=a,
                     label=unit)
        if k % cols:  # the first column names the rows
            a.set_ylabel('')
            a.set_yticklabels([])
    fig.suptitle(fitted_title(fig, f'{metric_label(metric)}: {note} '
                              '(mean over other axes; each panel its own '
                              'colour scale)'))
    return fig


def _sweep_scene(k, plot, scene, grids, layout, numeric, figdir):
    """The figures of one scene of a sweep: one file per method, then the
    small multiples; returns (small multiples' paths, all paths)."""
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    kind = grid_kind(plot, numeric, grids)
    note = f'{rend} vs {rend}:displacement, {scene}'
    written = []
    for m, g in grids.items():
        f1, a1 = plt.subplots(figsize=(5.8, 4.6), layout='constrained')
        f1.colorbar(draw_grid(a1, g, *layout, kind, f'{m}\n{note}'), ax=a1,
                    label=metric_label(metric).replace(' (', '\n(', 1))
        written += save(f1, figdir, f'plot-{k}-{stem(scene)}-{stem(metric)}-'
                        f'{stem(m)}')
    paths = save(panels_fig(grids, layout, kind, metric, note), figdir,
                 f'plot-{k}-{stem(scene)}')
    return paths, written + paths


def _sweep_scene_task(task):
    return _sweep_scene(*task)


def mean_grids(cells, scene, ox, oy, methods=None):
    """{method: mean grid} of one scene (None: every scene pooled)."""
    acc = {}
    for (s, m), a in cells.items():
        if (scene is None or s == scene) and (methods is None or
                                              m in methods):
            acc[m] = acc.get(m, 0) + a
    order = list(methods) if methods is not None else list(acc)
    with np.errstate(invalid='ignore', divide='ignore'):
        return {m: (acc[m][0] / acc[m][1])[np.ix_(oy, ox)]
                for m in order if m in acc}


def sweep_figures(k, plot, doc, src, figdir):
    """plots[k] of the report: per scene, the metric over axes[x] x axes[y]
    (mean over the other axes): small multiples plot-<k>-<scene>.* and one
    file per method. Returns {'metric', 'renderer', 'scenes': [(scene,
    small multiples' PNG)], 'written': [every path]}."""
    x, y, xs, ys, labels, numeric, ox, oy = sweep_layout(doc, src, k, plot)
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    cells = sweep_cells(doc, objs(doc.get('axes')), x, y, metric, rend)
    result = {'metric': metric, 'renderer': rend, 'scenes': [],
              'written': []}
    tasks = [(k, plot, scene, mean_grids(cells, scene, ox, oy),
              (xs, ys, labels), numeric, figdir)
             for scene in dict.fromkeys(s for s, _ in cells)]
    with worker_pool(len(tasks)) as pool:  # a scene's figures per process
        for task, (paths, written) in zip(tasks,
                                          pool.imap(_sweep_scene_task, tasks)):
            result['scenes'].append((task[2], paths[0]))
            result['written'] += written
    return result


def heatmap_fig(doc, src, plot, scene, methods, style):
    """The figure command's heatmap: plots-like {'metric', 'x', 'y',
    'kind', 'renderer'} over one scene (None: all scenes pooled) for the
    given methods; None when no cell has a value."""
    x, y, xs, ys, labels, numeric, ox, oy = sweep_layout(doc, src, 0, plot)
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    cells = sweep_cells(doc, objs(doc.get('axes')), x, y, metric, rend)
    grids = mean_grids(cells, scene, ox, oy, methods)
    if not grids:
        return None
    note = f'{rend} vs {rend}:displacement, ' + (
        f'scene {scene}' if scene else 'all scenes')
    return panels_fig(grids, (xs, ys, labels),
                      grid_kind(plot, numeric, grids), metric, note, style)
