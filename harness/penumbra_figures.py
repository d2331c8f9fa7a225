"""The matplotlib figures of a Penumbra study (the bump-mapping section).

Every figure is written as NAME.png, NAME.svg and NAME.pdf into the given
folder; the functions return the paths they wrote, PNG first (the page
embeds the PNG). report_figures() draws all of a report's figures, the
low-poly ones included, in a fixed order, which is the order report.py
prints them in. No HTML here: penumbra_html embeds what these return.
"""
import math
import os

import numpy as np
from matplotlib.ticker import LogFormatter, MaxNLocator

from penumbra_data import (
    FRACTION, GROUND_TRUTH, METRICS, REF, BadInput, axis_index, axis_labels, column, farray, fmt,
    get_metric, metric_label, num, obj, objs, stem)
from penumbra_filtering import filtering_figures
from penumbra_grid_figure import grid_figure
from penumbra_lowpoly_figures import lowpoly_figures
from penumbra_plot import (
    contour_lines, fitted_title, method_colors, plt, progress, save,
    worker_pool)

L_LABEL = 'L / (albedo·E/π)'


def report_colors(report):
    """The method colours of the bump section: every method named anywhere
    in the report, in order of first appearance."""
    return method_colors(
        [str(m) for r in report.renderers for m in r.get('methods') or []] +
        [str(e.get('method')) for _, g in report.ranking_groups()
         for e in g] +
        [str(r.get('method')) for v in report.variants
         for r in objs(v.get('renders'))] +
        [str(c.get('method')) for c in report.comps])


def profile_xy(p):
    """(theta bin centres, values) of the bins that hold samples, or None."""
    b, v = num(obj(p).get('bin_degrees')), farray(obj(p).get('value'))
    c = farray(obj(p).get('count'))
    ok = np.isfinite(v) & ((c > 0) if c.size == v.size else True)
    if not (b > 0 and ok.any()):
        return None
    return ((np.arange(v.size) + 0.5) * b)[ok], v[ok]


def percent_label(metric):
    """(scale, axis label) of a metric drawn in the page's unit: fractions
    of albedo·E/π as percent of it, everything else as it is."""
    name, unit = METRICS.get(metric, (metric, ''))
    if unit == FRACTION:
        return 100.0, f'{name} (% of albedo·E/π)'
    return 1.0, metric_label(metric)


def ranking_figure(rk, colors, figdir):
    """figures/ranking.*: the overall ranking and the per-scene means; []
    when the ranking is empty."""
    overall, scenes = objs(rk.get('overall')), objs(rk.get('per_scene'))
    if not overall and not any(objs(s.get('methods')) for s in scenes):
        return []
    methods = list(dict.fromkeys(str(e.get('method')) for e in overall + [
        e for s in scenes for e in objs(s.get('methods'))]))
    n = max(len(methods), 1)
    scale, xlabel = percent_label(rk.get('metric', 'profile.rmse_terminator'))
    fig, (ax, ag) = plt.subplots(1, 2, figsize=(11, 1.2 + 0.35 * max(
        n, len(scenes) * n * 0.6)), layout='constrained')
    vals = [num(e.get('mean')) * scale for e in overall]
    y = np.arange(len(overall))
    ax.barh(y, np.nan_to_num(vals), color=[colors[str(e.get('method'))]
                                           for e in overall])
    for yi, v in zip(y, vals):
        ax.text(np.nan_to_num(v), yi, ' ' + fmt(v), va='center', fontsize=8)
    ax.set_yticks(y, [str(e.get('method')) for e in overall])
    ax.set_title(f'overall (mean over variants), reference '
                 f'{rk.get("reference", "?")}')
    ax.margins(x=0.15)
    h = 0.8 / n
    for j, m in enumerate(methods):
        bars = [(i + (j - (n - 1) / 2) * h, num(e.get('mean')) * scale)
                for i, s in enumerate(scenes) for e in objs(s.get('methods'))
                if str(e.get('method')) == m and math.isfinite(
                    num(e.get('mean')))]
        ag.barh([b[0] for b in bars], [b[1] for b in bars], height=h,
                color=colors[m], label=m)
    ag.set_yticks(range(len(scenes)), [str(s.get('scene')) for s in scenes])
    ag.set_title('per scene')
    if methods:  # beside the panel: inside, it covers bars
        ag.legend(title='method', loc='upper left', bbox_to_anchor=(1.01, 1))
    for a in (ax, ag):
        a.invert_yaxis()
        a.set_xlabel(xlabel)
    return save(fig, figdir, 'ranking')


def _interval_bars(ax, methods, order, colors, title):
    """Horizontal bars of each method's combined relative error in % of raw
    bump's, with its 95 % interval as error bars, in the given method order
    (the same in every panel); methods without a finite value left out."""
    at = {str(m.get('method')): m for m in methods}
    rows = [(name, 100 * num(at[name].get('combined_relative_error')),
             at[name].get('combined_ci')) for name in order if name in at]
    rows = [r for r in rows if math.isfinite(r[1])]
    y = [order.index(r[0]) for r in rows]

    def bound(ci, k):
        ok = isinstance(ci, list) and len(ci) == 2 and ci[k] is not None
        return 100 * num(ci[k]) if ok else math.nan
    lo = [max(r[1] - bound(r[2], 0), 0) if math.isfinite(bound(r[2], 0))
          else 0 for r in rows]
    hi = [max(bound(r[2], 1) - r[1], 0) if math.isfinite(bound(r[2], 1))
          else 0 for r in rows]
    ax.barh(y, [r[1] for r in rows], xerr=[lo, hi], capsize=3,
            color=[colors.get(r[0], 'grey') for r in rows])
    ax.axvline(100.0, color='black', linewidth=0.8, linestyle='--')
    ax.set_title(title, fontsize=9)


def statistics_figure(st, colors, figdir):
    """figures/statistics.*: each method's combined relative error in % of
    raw bump's, with its 95 % bootstrap interval over variants, overall and
    per scene: panels on a grid of at most three columns, methods in the
    overall order in every panel; [] without statistics."""
    overall = obj(st.get('overall'))
    scenes = [s for s in objs(st.get('per_scene')) if objs(s.get('methods'))]
    order = [str(m.get('method')) for m in objs(overall.get('methods'))]
    if not order:
        return []
    panels = [('all variants', overall)] + [(str(s.get('scene')), s)
                                            for s in scenes]
    cols = min(3, len(panels))
    rows = -(-len(panels) // cols)
    fig, axes = plt.subplots(rows, cols, sharey=True, squeeze=False,
                             figsize=(3.6 * cols + 1.6,
                                      rows * (1.4 + 0.3 * len(order))),
                             layout='constrained')
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    for ax, (title, s) in zip(axes.flat, panels):
        _interval_bars(ax, objs(s.get('methods')), order, colors,
                       f'{title} ({s.get("variants", "?")} variants)')
        # Log scale: a method 10x worse than raw bump would flatten the rest.
        ax.set_xscale('log')
        # Plain numbers (60, 100, 300), not 6×10¹: a reader compares them.
        ax.xaxis.set_major_formatter(LogFormatter(labelOnlyBase=False))
        ax.xaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False,
                                                  minor_thresholds=(1, 0.5)))
        ax.set_xlabel('combined error, % of raw bump\'s\n(log scale; '
                      '95 % CI; dashed: raw bump)', fontsize=8)
    axes[0][0].set_yticks(range(len(order)), order)
    axes[0][0].invert_yaxis()
    return save(fig, figdir, 'statistics')


def _profile_style(r, colors):
    """(legend label, line style) of one render in its renderer's panel."""
    meth, lab = str(r.get('method')), column(r)
    if lab == GROUND_TRUTH:
        return lab, dict(color='k', lw=2.4, zorder=5)
    return lab, dict(color=colors[meth], lw=1.3)


def _by_renderer(renders):
    """{renderer: {'truth': its displacement profile or None, 'series':
    [(render, (x, y))]}}, the evaluator first, then the others sorted."""
    groups = {}
    for r in renders:
        xy = profile_xy(r.get('profile'))
        if xy is None:
            continue
        g = groups.setdefault(str(r.get('renderer')),
                              {'truth': None, 'series': []})
        if r.get('representation') == 'displacement':
            g['truth'] = xy
        g['series'].append((r, xy))
    order = ([REF] if REF in groups else []) + sorted(set(groups) - {REF})
    return {k: groups[k] for k in order}


def profile_xlim(groups, region):
    """The angles the data covers: from the first bin with samples to 5°
    past the last bin where any profile is still above 0.1 % of albedo·E/π
    (the shadow beyond is all zeros), at least to the terminator region's
    end."""
    xs = [xy[0] for g in groups.values() for _, xy in g['series']]
    lit = [xy[0][np.abs(xy[1]) > 1e-3] for g in groups.values()
           for _, xy in g['series']]
    lit = [x for x in lit if x.size]
    lo = min(x.min() for x in xs)
    hi = max([x.max() for x in lit] + [region[1] - 5])
    return max(0.0, lo - 1), min(180.0, hi + 5)


def _profile_panels(ax, ad, rend, g, gt, colors, region):
    """One renderer's column: its profiles over the evaluator's truth, and
    each minus the renderer's own displacement truth (the external
    renderer's truth also minus the evaluator's)."""
    own = g['truth']
    if rend != REF and gt is not None:
        ax.plot(*gt, color='0.6', lw=3.5, zorder=1,
                label=f'{REF} ground truth')
    for r, xy in g['series']:
        lab, style = _profile_style(r, colors)
        span = (xy[0][-1] - xy[0][0]) / num(r['profile']['bin_degrees'])
        if xy[0].size < 0.6 * span:  # sparse: mark the bins
            style.update(marker='.', ms=4)
        ax.plot(*xy, label=lab, **style)
        if column(r) == GROUND_TRUTH:
            if rend != REF and gt is not None:
                ad.plot(xy[0], xy[1] - np.interp(xy[0], *gt, left=math.nan,
                                                 right=math.nan),
                        color='0.4', lw=1.2, ls=(0, (4, 2)),
                        label=f'{rend} truth − {REF} truth')
            continue
        if own is not None:
            ad.plot(xy[0], xy[1] - np.interp(xy[0], *own, left=math.nan,
                                             right=math.nan), **style)
    for a in (ax, ad):
        a.axvspan(*region, color='0.92', zorder=0)
        a.grid(alpha=0.3)
    ad.axhline(0, color='k', lw=0.8)
    ax.set_title(rend)
    ad.set_title(f'minus {rend}\'s displacement truth' if own is not None
                 else f'no {rend} displacement render', fontsize=9)


def profile_figure(var, colors, region, figdir):
    """figures/profiles-<variant>.*: L(theta) of every render of a variant,
    a column per renderer (its methods over the evaluator's truth) and,
    below, each method minus the same renderer's displacement truth; the
    angle axis cropped to the data; empty bins bridged (dots mark the bins
    when they are sparse)."""
    groups = _by_renderer(objs(var.get('renders')))
    if not groups:
        groups = {REF: {'truth': None, 'series': []}}
    gt = groups.get(REF, {}).get('truth')
    n = len(groups)
    fig, axs = plt.subplots(2, n, figsize=(4.6 * n + 2.2, 6.8), sharex=True,
                            sharey='row', squeeze=False,
                            height_ratios=[3, 2], layout='constrained')
    for k, (rend, g) in enumerate(groups.items()):
        _profile_panels(axs[0][k], axs[1][k], rend, g, gt, colors, region)
        axs[1][k].set_xlabel('θ: light vs base normal (degrees)')
    if any(g['series'] for g in groups.values()):
        axs[0][0].set_xlim(*profile_xlim(groups, region))
    axs[0][0].set_ylabel(L_LABEL)
    axs[1][0].set_ylabel(f'Δ{L_LABEL}')
    handles = {}
    for a in axs.flat:
        for h, lab in zip(*a.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    handles[f'terminator region {region[0]:g}–{region[1]:g}°'] = \
        plt.Rectangle((0, 0), 1, 1, color='0.92')
    # Beside the panels (matplotlib 3.6 has no 'outside' placement): the
    # tight bounding box of save() takes it in.
    fig.legend(handles.values(), handles.keys(), loc='upper left',
               bbox_to_anchor=(1.0, 0.95))
    fig.suptitle(fitted_title(
        fig, f'terminator profiles: {var.get("label", var.get("id"))}'))
    return save(fig, figdir, f'profiles-{stem(var.get("id"))}')


def geometric(v):
    """Whether positive values are more evenly spaced on a log scale."""
    v = np.sort(np.asarray(v, dtype=float))
    if v.size < 3 or v[0] <= 0:
        return False

    def cv(d):
        return np.std(d) / np.mean(d) if np.mean(d) > 0 else math.inf
    return cv(np.diff(np.log(v))) < cv(np.diff(v))


def _draw_contour(ax, grid, xs, ys, xt, yt, cmap, norm):
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


def draw_grid(ax, grid, xs, ys, labels, kind, lim, title):
    """One panel: contour when kind == 'contour', else annotated heatmap;
    colours span lim = (vmin, vmax); labels: (x label, y label, x tick
    texts, y tick texts)."""
    cmap, norm = plt.get_cmap('viridis'), plt.Normalize(*lim)  # own norm:
    # one shared by several figures breaks matplotlib 3.6 at close
    xt, yt = labels[2], labels[3]  # tick texts
    if kind == 'contour':
        im = _draw_contour(ax, grid, xs, ys, xt, yt, cmap, norm)
    else:
        im = ax.imshow(grid, origin='lower', cmap=cmap, norm=norm,
                       aspect='auto')
        for (i, j), v in np.ndenumerate(grid):
            lum = np.dot(cmap(norm(v))[:3], [0.299, 0.587, 0.114])
            ax.text(j, i, fmt(v), ha='center', va='center', fontsize=8,
                    color='w' if lum < 0.5 and math.isfinite(v) else 'k')
        ax.set_xticks(range(len(xs)), xt, rotation=30, ha='right')
        ax.set_yticks(range(len(ys)), yt)
    ax.set(xlabel=labels[0], ylabel=labels[1], title=title)
    return im


def _sweep_cells(doc, axes, x, y, metric, rend):
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


def _sweep_scene(k, plot, scene, grids, xs, ys, labels, numeric, figdir):
    """The figures of one scene of a sweep: one file per method, then the
    small multiples; returns (small multiples' paths, all paths)."""
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    scale, label = percent_label(metric)
    # Two lines: one long line is clipped beside a colour bar.
    label = label.replace(' (', '\n(', 1)
    grids = {m: g * scale for m, g in grids.items()}
    allv = np.concatenate([g[np.isfinite(g)] for g in grids.values()])
    lo, hi = allv.min(), allv.max()
    pad = 0 if hi > lo else max(abs(lo) * 0.05, 1e-6)  # constant data
    lim = (lo - pad, hi + pad)
    kind = 'contour' if plot.get('kind', 'contour') == 'contour' and \
        numeric and all(np.isfinite(g).sum() >= 4
                        for g in grids.values()) else 'heatmap'
    note = f'{rend} vs {rend}:displacement, {scene}'
    cols = min(len(grids), 3)
    rows = -(-len(grids) // cols)
    fig, axs = plt.subplots(rows, cols, squeeze=False,
                            figsize=(4.2 * cols + 1, 4.2 * rows + 0.4),
                            layout='constrained')
    for a in axs.flat[len(grids):]:
        a.set_visible(False)
    written = []
    for a, (m, g) in zip(axs.flat, grids.items()):
        im = draw_grid(a, g, xs, ys, labels, kind, lim, m)
        f1, a1 = plt.subplots(figsize=(5.8, 4.6), layout='constrained')
        f1.colorbar(draw_grid(a1, g, xs, ys, labels, kind, lim,
                              f'{m}\n{note}'),
                    ax=a1, label=label)
        written += save(f1, figdir, f'plot-{k}-{stem(scene)}-{stem(metric)}-'
                        f'{stem(m)}')
    fig.colorbar(im, ax=axs.ravel().tolist(), label=label)
    fig.suptitle(fitted_title(
        fig, f'{metric_label(metric).replace(FRACTION, "% of albedo·E/π")}'
        f': {note} (mean over other axes)'))
    paths = save(fig, figdir, f'plot-{k}-{stem(scene)}')
    return paths, written + paths


def sweep_figures(k, plot, doc, src, figdir):
    """plots[k] of the report: per scene, the metric over axes[x] x axes[y]
    (mean over the other axes): small multiples plot-<k>-<scene>.* and one
    file per method. Returns {'metric', 'renderer', 'scenes': [(scene,
    small multiples' PNG)], 'written': [every path]}."""
    axes = objs(doc.get('axes'))
    x, y = plot.get('x'), plot.get('y')
    if x == y or not all(type(i) is int and 0 <= i < len(axes)
                         for i in (x, y)):
        raise BadInput(src, f'plots[{k}]: x and y must be two different '
                       f'indices into axes (0..{len(axes) - 1}), got {x!r}, '
                       f'{y!r}')
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    cells = _sweep_cells(doc, axes, x, y, metric, rend)
    xs, ys = axes[x]['values'], axes[y]['values']
    numeric = all(len(v) >= 2 and all(math.isfinite(num(t)) for t in v)
                  for v in (xs, ys))
    ox, oy = (np.argsort([num(t) for t in v]) if numeric
              else np.arange(len(v)) for v in (xs, ys))
    xs, ys = [xs[i] for i in ox], [ys[i] for i in oy]
    xt, yt = ([axis_labels(axes[a])[i] for i in o]
              for a, o in ((x, ox), (y, oy)))
    labels = [str(axes[i].get('label', axes[i].get('pointer')))
              for i in (x, y)] + [xt, yt]
    result = {'metric': metric, 'renderer': rend, 'scenes': [],
              'written': []}
    tasks = []
    for scene in dict.fromkeys(s for s, _ in cells):
        with np.errstate(invalid='ignore', divide='ignore'):
            grids = {m: (a[0] / a[1])[np.ix_(oy, ox)]
                     for (s, m), a in cells.items() if s == scene}
        tasks.append((k, plot, scene, grids, xs, ys, labels, numeric, figdir))
    with worker_pool(len(tasks)) as pool:  # a scene's figures per process
        for task, (paths, written) in zip(tasks,
                                          pool.imap(_sweep_scene_task, tasks)):
            result['scenes'].append((task[2], paths[0]))
            result['written'] += written
    return result


def _sweep_scene_task(task):
    return _sweep_scene(*task)


def _call(task):
    """task = (function, arguments): for a pool of unlike figures."""
    function, arguments = task
    return function(*arguments)


def _variant_figures(task):
    """A variant's profile figure and composed image grid (run in a worker
    process: each figure depends on its inputs alone, so the bytes are the
    same whichever process draws it)."""
    v, colors, terminator, out, src, names, figdir = task
    return (profile_figure(v, colors, terminator, figdir),
            grid_figure(v, out, src, names, figdir))


def report_figures(report):
    """Every figure of a report into OUT/figures, in the order report.py
    prints them: ranking, profiles per variant, sweeps, then the low-poly
    section. Returns {'ranking': PNG or None, 'profiles': [PNG per
    shown variant (report.shown)], 'grids': [[PNG, PDF] or [] per shown
    variant], 'sweeps': [sweep_figures()], 'lowpoly': lowpoly_figures() or
    None, 'filtering': [paths per report.filtering entry, PNG, SVG, PDF
    per metric], 'written': [every path]}."""
    figdir = os.path.join(report.out, 'figures')
    os.makedirs(figdir, exist_ok=True)
    colors = report_colors(report)
    progress('ranking and statistics figures')
    with worker_pool(2) as pool:
        written, stats = list(pool.imap(_call, [
            (ranking_figure, (report.ranking, colors, figdir)),
            (statistics_figure, (obj(report.doc.get('statistics')), colors,
                                 figdir))]))
    figs = {'ranking': written[0] if written else None, 'profiles': [],
            'sweeps': [], 'lowpoly': None}
    figs['statistics'] = stats[0] if stats else None
    written += stats
    figs['grids'] = []
    names = [str(r.get('id')) for r in report.renderers]
    tasks = [(v, colors, report.terminator, report.out, report.src, names,
              figdir) for v in report.shown]
    with worker_pool(len(tasks)) as pool:
        for k, (paths, grid) in enumerate(pool.imap(_variant_figures, tasks)):
            progress(f'profiles and image grid of {report.shown[k].get("id")}'
                     f' ({k + 1}/{len(report.shown)} variants)')
            figs['profiles'].append(paths[0])
            figs['grids'].append(grid)
            written += paths + grid
    for k, plot in enumerate(report.doc.get('plots', [])):
        if not isinstance(plot, dict):
            raise BadInput(report.src, f'plots[{k}] must be an object')
        progress(f'sweep {k + 1}/{len(report.doc.get("plots", []))}: '
                 f'{plot.get("metric")}')
        sweep = sweep_figures(k, plot, report.doc, report.src, figdir)
        figs['sweeps'].append(sweep)
        written += sweep['written']
    if report.lowpoly:
        progress('low-poly section')
        figs['lowpoly'] = lowpoly_figures(report.lowpoly, figdir)
        written += figs['lowpoly']['written']
    figs['filtering'] = []
    for k, e in enumerate(report.filtering):
        progress(f'filtering {e["map"]}/{e["run"]} '
                 f'({k + 1}/{len(report.filtering)})')
        paths = filtering_figures(e['path'], figdir,
                                  f'filtering-{e["map"]}-{e["run"]}')
        figs['filtering'].append(paths)
        written += paths
    figs['written'] = written
    return figs
