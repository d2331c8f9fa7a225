"""The matplotlib figures of a Penumbra study (the bump-mapping section):
the profile figures here, the others in penumbra_paper_figures (ranking,
statistics, line), penumbra_sweeps and penumbra_grid_figure.

Every figure is written as NAME.png, NAME.svg and NAME.pdf into the given
folder (the image grids PNG and PDF); the functions return the paths they
wrote, PNG first (the page embeds the PNG). report_figures() draws all of a report's figures, the
low-poly ones included, in a fixed order, which is the order report.py
prints them in. No HTML here: penumbra_html embeds what these return.
"""
import math
import os

import numpy as np

from penumbra_data import (
    FRACTION, GROUND_TRUTH, PRIMARY, REF, BadInput, column, farray, num, obj,
    objs, stem)
from penumbra_filtering import filtering_figures
from penumbra_grid_figure import grid_figure
from penumbra_lowpoly_figures import lowpoly_figures
from penumbra_paper_figures import (
    line_fig, mean_rmse_fig, ranking_fig, statistics_fig)
from penumbra_plot import fitted_title, plt, progress, save, worker_pool
from penumbra_stats import highlighted, line_methods
from penumbra_style import SCREEN, series_styles
from penumbra_sweeps import sweep_figures

L_LABEL = f'L ({FRACTION})'
THETA_LABEL = 'θ: light vs base normal (degrees)'


def report_methods(report):
    """Every method named anywhere in the bump section, in order of first
    appearance (the study's order): the palette's order."""
    return list(dict.fromkeys(
        [str(m) for r in report.renderers for m in r.get('methods') or []] +
        [str(e.get('method')) for _, g in report.ranking_groups()
         for e in g] +
        [str(r.get('method')) for v in report.variants
         for r in objs(v.get('renders'))] +
        [str(c.get('method')) for c in report.comps]))


def report_styles(report, stats):
    """{method: {'color', 'ls', 'marker'}}: one look per method in every
    figure of the report and of `report.py figure`. The palette is dealt
    in this order: the highlighted methods (so the handful a figure shows
    by default have nine colours to themselves, and solid lines), then
    the rank order, then every other method as the report names it."""
    methods = report_methods(report)
    return series_styles(figure_methods(report, stats) + stats.methods +
                         methods)


def profile_xy(p):
    """(theta bin centres, values) of the bins that hold samples, or None."""
    b, v = num(obj(p).get('bin_degrees')), farray(obj(p).get('value'))
    c = farray(obj(p).get('count'))
    ok = np.isfinite(v) & ((c > 0) if c.size == v.size else True)
    if not (b > 0 and ok.any()):
        return None
    return ((np.arange(v.size) + 0.5) * b)[ok], v[ok]


def _profile_style(r, styles, marks, k):
    """(legend label, line style) of the k-th render in its renderer's
    panel; marks: markers along the line too (the all-methods figure,
    where colour and dash alone repeat past 9 and 36 series). Without
    marks each line is thinner than the one before, so that a method
    whose profile equals an earlier one's still shows under it."""
    meth, lab = str(r.get('method')), column(r)
    if lab == GROUND_TRUTH:
        return lab, dict(color='k', lw=2.4, zorder=5)
    st = styles.get(meth, {'color': 'k', 'ls': '-', 'marker': ''})
    style = dict(color=st['color'], ls=st['ls'],
                 lw=1.3 if marks else max(0.7, 2.2 - 0.35 * k))
    if marks and st['marker']:
        style.update(marker=st['marker'], ms=3.5, markevery=0.12)
    return lab, style


def _by_renderer(renders, methods=None):
    """{renderer: {'truth': its displacement profile or None, 'series':
    [(render, (x, y))]}}, the evaluator first, then the others sorted;
    bump renders of `methods` only (all when None), in that order."""
    groups = {}
    rank = {m: i for i, m in enumerate(methods or [])}
    for r in renders:
        xy = profile_xy(r.get('profile'))
        truth = r.get('representation') == 'displacement'
        if xy is None or not (truth or methods is None or
                              str(r.get('method')) in rank):
            continue
        g = groups.setdefault(str(r.get('renderer')),
                              {'truth': None, 'series': []})
        if truth:
            g['truth'] = xy
        g['series'].append((r, xy))
    for g in groups.values():  # the truth first, then the given order
        g['series'].sort(key=lambda s: -1 if column(s[0]) == GROUND_TRUTH
                         else rank.get(str(s[0].get('method')), 0))
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


def _profile_panels(ax, ad, rend, g, gt, look):
    """One renderer's column: its profiles over the evaluator's truth, and
    each minus the renderer's own displacement truth (the external
    renderer's truth also minus the evaluator's). look: (styles, region,
    marks)."""
    styles, region, marks = look
    own = g['truth']
    if rend != REF and gt is not None:
        ax.plot(*gt, color='0.6', lw=3.5, zorder=1,
                label=f'{REF} ground truth')
    for k, (r, xy) in enumerate(g['series']):
        lab, style = _profile_style(r, styles, marks, k)
        span = (xy[0][-1] - xy[0][0]) / num(r['profile']['bin_degrees'])
        if xy[0].size < 0.6 * span and 'marker' not in style:
            style.update(marker='.', ms=4)  # sparse: mark the bins
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
                 else f'no {rend} displacement render', fontsize=8)


def _profile_legend(fig, axs, region, lax=None, ncol=3):
    """One legend for every panel: beside them on screen (the tight
    bounding box of save() takes it in), or on paper in `lax`, an empty
    axes row under them (the page's width is fixed, and constrained
    layout in matplotlib 3.6 makes room for an axes, not a figure
    legend)."""
    handles = {}
    for a in axs.flat:
        for h, lab in zip(*a.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    handles[f'terminator region {region[0]:g}–{region[1]:g}°'] = \
        plt.Rectangle((0, 0), 1, 1, color='0.92')
    if lax is not None:
        lax.set_axis_off()
        lax.legend(handles.values(), handles.keys(), loc='center',
                   ncol=ncol, frameon=False, handlelength=1.5,
                   columnspacing=1.0)
    else:
        fig.legend(handles.values(), handles.keys(), loc='upper left',
                   bbox_to_anchor=(1.0, 0.95))


def _profile_axes(n, style, entries):
    """(figure, 2 x n data axes, legend axes or None)."""
    if not style.paper:
        fig, axs = plt.subplots(2, n, sharex=True, sharey='row',
                                squeeze=False, height_ratios=[3, 2],
                                layout='constrained',
                                figsize=(4.6 * n + 2.2, 6.8))
        return fig, axs, None
    rows = -(-entries // (style.columns + 1))  # the legend's rows
    fig = plt.figure(layout='constrained', figsize=(
        style.width(0), (3.0 if style.columns == 1 else 3.2) + 0.16 * rows))
    gs = fig.add_gridspec(3, n, height_ratios=[3, 2, 0.3 * rows])
    axs = np.empty((2, n), dtype=object)
    for k in range(n):
        axs[0][k] = fig.add_subplot(gs[0, k], sharex=axs[0][0] if k else None,
                                    sharey=axs[0][0] if k else None)
        axs[1][k] = fig.add_subplot(gs[1, k], sharex=axs[0][0],
                                    sharey=axs[1][0] if k else None)
        axs[0][k].tick_params(labelbottom=False)
        if k:
            for a in axs[:, k]:
                a.tick_params(labelleft=False)
    return fig, axs, fig.add_subplot(gs[2, :])


def profile_fig(var, styles, region, methods=None, style=SCREEN,
                marks=False):
    """L(theta) of a variant's renders (the bump renders of `methods`
    only, all when None), a column per renderer (its methods over the
    evaluator's truth) and, below, each method minus the same renderer's
    displacement truth; the angle axis cropped to the data; empty bins
    bridged (dots mark the bins when they are sparse). On paper one column
    wide, the evaluator's column only (three do not fit 3.5 in)."""
    groups = _by_renderer(objs(var.get('renders')), methods) or \
        {REF: {'truth': None, 'series': []}}
    gt = groups.get(REF, {}).get('truth')
    if style.paper and style.columns == 1:  # 3.5 in: the evaluator's alone
        groups = {k: g for k, g in groups.items() if k == REF} or groups
    fig, axs, lax = _profile_axes(len(groups), style, 2 + len(
        {str(r.get('method')) for g in groups.values() for r, _ in g['series']})
        + len(groups))
    for k, (rend, g) in enumerate(groups.items()):
        _profile_panels(axs[0][k], axs[1][k], rend, g, gt,
                        (styles, region, marks))
        axs[1][k].set_xlabel('θ (degrees)' if style.paper else THETA_LABEL)
        if style.paper:
            axs[1][k].set_title(f'− {rend} truth', fontsize=7)
    if any(g['series'] for g in groups.values()):
        axs[0][0].set_xlim(*profile_xlim(groups, region))
    axs[0][0].set_ylabel(L_LABEL.replace(' (', '\n(', 1))
    axs[1][0].set_ylabel(('Δ' + L_LABEL).replace(' (', '\n(', 1))
    _profile_legend(fig, axs, region, lax, style.columns + 1)
    if not style.paper:
        fig.suptitle(fitted_title(
            fig, f'terminator profiles: {var.get("label", var.get("id"))}' +
            ('' if methods is None else f' ({len(methods)} methods)')))
    return fig


def profile_figure(var, styles, region, figdir, methods=None):
    """figures/profiles-<variant>.{png,svg,pdf} (the given methods) or,
    methods None, all-methods-profiles-<variant>.png (every method,
    markers along the lines)."""
    every = methods is None
    fig = profile_fig(var, styles, region, methods, marks=every)
    # Every method's as PNG only: the page links it, and a figure for a
    # paper is the handful's or `report.py figure --methods all` (PDF).
    return save(fig, figdir, ('all-methods-profiles-' if every else
                              'profiles-') + stem(var.get('id')),
                ('png',) if every else ('png', 'svg', 'pdf'))


_SHARED = {}  # set before a pool forks: the workers inherit it


def _stats_figure(task):
    """One figure of the ranking statistics, drawn from _SHARED (stats,
    styles) in the screen style: (name, builder, arguments after stats and
    styles) -> its paths, [] when the builder has nothing to draw."""
    name, builder, args = task
    fig = builder(_SHARED['stats'], _SHARED['styles'], *args)
    return [] if fig is None else save(fig, _SHARED['figdir'], name)


def axis_stem(pointer):
    """A file-name part of an axis pointer: /height/amplitude ->
    height-amplitude."""
    return stem(str(pointer).strip('/').replace('/', '-'))


def _stats_tasks(stats, shown):
    """(key, task) of every statistics figure, in the order drawn."""
    tasks = [('ranking', ('ranking', ranking_fig, (SCREEN,))),
             ('statistics', ('statistics', statistics_fig, (SCREEN,)))]
    tasks += [(('line', a['pointer']),
               (f'line-{axis_stem(a["pointer"])}', line_fig_by,
                (a['pointer'], line_methods(shown, a))))
              for a in stats.by_axis()]
    return tasks


def line_fig_by(stats, styles, pointer, methods):
    """line_fig of the primary metric over the axis `pointer`."""
    return line_fig(stats, stats.axis(pointer), PRIMARY, methods, styles,
                    SCREEN)


def statistics_figures(stats, styles, shown, figdir):
    """The ranking, statistics, mean-RMSE and line figures: {'ranking',
    'statistics', 'mean_rmse': PNG or None, 'lines': [(axis entry, PNG)],
    'written': [paths]}."""
    stats.by_axis()  # computed once, before the workers fork
    _SHARED.update(stats=stats, styles=styles, figdir=figdir)
    tasks = _stats_tasks(stats, shown) + [
        ('mean_rmse', ('mean-rmse-terminator', mean_rmse_fig, (SCREEN,)))]
    out = {'ranking': None, 'statistics': None, 'mean_rmse': None,
           'lines': [], 'written': []}
    with worker_pool(len(tasks)) as pool:
        for (key, _), paths in zip(tasks, pool.imap(
                _stats_figure, [t for _, t in tasks])):
            out['written'] += paths
            if isinstance(key, tuple):
                out['lines'].append((stats.axis(key[1]),
                                     paths[0] if paths else None))
            else:
                out[key] = paths[0] if paths else None
    return out


def _variant_figures(task):
    """A variant's profile figures, the highlighted methods' and every
    method's, and its image grid (run in a worker process: each figure
    depends on its inputs alone, so the bytes are the same whichever
    process draws it)."""
    v, shown, names = task
    styles, region, out, src, figdir = _SHARED['variant']
    return (profile_figure(v, styles, region, figdir, shown),
            profile_figure(v, styles, region, figdir, None),
            grid_figure(v, out, src, names, figdir, shown))


def variant_figures(report, styles, shown, figdir):
    """Every shown variant's figures: {'profiles', 'profiles_all': [PNG
    per shown variant], 'grids': [[PNG, PDF] or []], 'written': [paths]}."""
    names = [str(r.get('id')) for r in report.renderers]
    _SHARED['variant'] = (styles, report.terminator, report.out, report.src,
                          figdir)
    out = {'profiles': [], 'profiles_all': [], 'grids': [], 'written': []}
    tasks = [(v, shown, names) for v in report.shown]
    with worker_pool(len(tasks)) as pool:
        for k, (p, pa, g) in enumerate(pool.imap(_variant_figures, tasks)):
            progress(f'profiles and image grid of '
                     f'{report.shown[k].get("id")} ({k + 1}/'
                     f'{len(report.shown)} variants)')
            out['profiles'].append(p[0])
            out['profiles_all'].append(pa[0])
            out['grids'].append(g)
            out['written'] += p + pa + g
    return out


def figure_methods(report, stats):
    """The handful of methods the profile, line and grid figures show:
    penumbra_stats.highlighted, with the study's figures.methods named."""
    named = [str(m) for m in obj(report.doc.get('figures')).get('methods')
             or [] if isinstance(m, str)]
    return highlighted(stats, report_methods(report), named)


def report_figures(report, stats):
    """Every figure of a report into OUT/figures, in the order report.py
    prints them: ranking statistics, profiles and grids per variant,
    sweeps, then the low-poly and filtering sections. Returns
    statistics_figures()'s keys, variant_figures()'s keys, 'shown' (the
    highlighted methods), 'sweeps': [sweep_figures()], 'lowpoly':
    lowpoly_figures() or None, 'filtering': [paths per report.filtering
    entry, PNG, SVG, PDF per metric], 'written': [every path]."""
    figdir = os.path.join(report.out, 'figures')
    os.makedirs(figdir, exist_ok=True)
    styles = report_styles(report, stats)
    shown = figure_methods(report, stats)
    progress('ranking, statistics and line figures')
    figs = statistics_figures(stats, styles, shown, figdir)
    written = figs.pop('written')
    figs.update(variant_figures(report, styles, shown, figdir), shown=shown,
                stats=stats, sweeps=[], lowpoly=None, filtering=[])
    written += figs.pop('written')
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
    for k, e in enumerate(report.filtering):
        progress(f'filtering {e["map"]}/{e["run"]} '
                 f'({k + 1}/{len(report.filtering)})')
        paths = filtering_figures(e['path'], figdir,
                                  f'filtering-{e["map"]}-{e["run"]}')
        figs['filtering'].append(paths)
        written += paths
    figs['written'] = written
    return figs
