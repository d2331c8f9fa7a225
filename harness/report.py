#!/usr/bin/python3
"""Figures and a self-contained HTML page for a Penumbra study.

Usage (Debian's Python, which has matplotlib and numpy):
  /usr/bin/python3 harness/report.py report OUT
      reads OUT/report.json; writes OUT/figures/*.{png,svg,pdf} and
      OUT/report.html (every image embedded as a data: URI).
  /usr/bin/python3 harness/report.py contour CONTOUR.json OUTDIR
      writes OUTDIR/contour-<method>.*, contour-diff-<a>-<b>.* for every
      pair of methods in the given order, and the combined contour.*.

Prints every written file, one a line. Exit status 0 ok; 2 bad input
(missing file, malformed JSON, wrong format or version, a path outside OUT),
one line on stderr: "report.py: <file>: <what>"; 1 an output error.
Nothing from the JSON is executed; every string from it is HTML-escaped.
The same input gives the same bytes (no dates or versions in the files).

report.json ("format": "penumbra-report", "version": 1; any number may be
null): penumbra, study{name,file}, units{}, axes[{pointer,label,values}],
renderers[{id,version,methods[],note}], variants[{id,scene,label,
axis_values[], renders[{renderer,representation,method,image,difference,
profile{bin_degrees,value[],count[]}}]}], comparisons[{variant,scene,
renderer,method,reference,profile{rmse_terminator,...},image{rmse,ssim,...}}],
ranking{metric,reference,renderer,per_scene[{scene,methods[{method,mean,
count}]}],overall[...]}, missing[{renderer,method,why}],
failures[{render,error}], plots[{metric,x,y,kind,renderer}], lowpoly (null,
or the low-poly section: axes[], convergence_axis (an axes pointer or null),
renderers[{id,offsets[]}], missing[{renderer,offset or scene,why}],
variants[{id,scene,label,axis_values[],renders[{renderer,offset ("analytic":
the untessellated truth),triangles,image,difference,exr,profile{}}]}],
comparisons[{variant,scene,axis_values[],renderer,offset,reference
("<renderer>:analytic"),shadow{darkened_fraction,max_darkening,
lost_shadow_fraction,shadow_shift_px,shadowed_pixels,...},profile{},
image{}}], ranking{metric,reference,renderer,per_scene[{scene,offsets[{offset,
darkened_fraction,rmse_terminator,count}]}],overall[...]}, units{}). image
and difference are PNG paths relative to OUT.

The low-poly section (after the bump one) draws figures/lowpoly-convergence-
<group>.* (evaluator offsets vs evaluator:analytic over the convergence axis),
lowpoly-external-<group>.* (other renderers vs their own analytic render) and
lowpoly-shadow-<group>.* (cast-shadow loss and shift, scenes with a cast
shadow); a group is a scene plus the values of any other axes.

contour JSON ("format": "penumbra-contour", "version": 1): light_deg[],
deviation_deg[], methods[{id, G[deviation][light]}] (null: undefined).
"""
import base64
import html
import json
import math
import os
import re
import sys

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import patheffects  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

plt.rcParams.update({'svg.hashsalt': 'penumbra', 'font.size': 10,
                     'axes.titlesize': 11, 'legend.fontsize': 8})
META = {'png': {'Software': None}, 'svg': {'Date': None, 'Creator': None},
        'pdf': {'CreationDate': None, 'Creator': None, 'Producer': None}}
REF = 'evaluator'                 # the renderer whose displacement is truth
FRACTION = 'fraction of albedo·E/π'
L_LABEL = 'L / (albedo·E/π)'
METRICS = {                       # metric -> (name, unit)
    'profile.rmse_terminator': ('terminator-region profile RMSE', FRACTION),
    'profile.rmse_overall': ('profile RMSE, all bins', FRACTION),
    'profile.max_error_terminator': ('max terminator error', FRACTION),
    'profile.max_step': ('largest profile step', FRACTION),
    'profile.position_error_deg': ('terminator position error', 'degrees'),
    'profile.width_deg': ('terminator width', 'degrees'),
    'profile.lit_bias': ('lit-region bias', FRACTION),
    'image.rmse': ('image RMSE', 'W m⁻² sr⁻¹'),
    'image.ssim': ('image SSIM', 'unitless'),
    'image.mask_iou': ('silhouette IoU', 'unitless')}
GROUND_TRUTH = 'ground truth (displacement)'


class BadInput(Exception):
    """Bad input: reported as 'report.py: <file>: <what>', exit status 2."""

    def __init__(self, file, what):
        super().__init__(f'{file}: {what}')


def esc(x):
    return html.escape(str(x), quote=True)


def num(x):
    """A JSON number as float; nan for null or anything else."""
    ok = isinstance(x, (int, float)) and not isinstance(x, bool)
    return float(x) if ok else math.nan


def farray(xs):
    return np.array([num(v) for v in (xs if isinstance(xs, list) else [])],
                    dtype=float)


def obj(x):
    return x if isinstance(x, dict) else {}


def objs(x):
    """The objects of a JSON array (anything else: none)."""
    return [e for e in x if isinstance(e, dict)] if isinstance(x, list) else []


def stem(s):
    """A string from the JSON made safe as part of a file name."""
    return re.sub(r'[^A-Za-z0-9_.+-]', '_', str(s)).lstrip('.') or '_'


def metric_label(metric):
    name, unit = METRICS.get(metric, (metric, ''))
    return f'{name} ({unit})' if unit else name


def fmt(x, scale=1.0, digits=3):
    x = num(x)
    return 'n/a' if not math.isfinite(x) else f'{x * scale:.{digits}g}'


def load_json(path, fmt_name):
    try:
        with open(path, encoding='utf-8') as f:
            data = json.load(f)
    except FileNotFoundError:
        raise BadInput(path, 'no such file')
    except (OSError, UnicodeDecodeError) as e:
        raise BadInput(path, f'cannot read: {e}')
    except json.JSONDecodeError as e:
        raise BadInput(path, f'malformed JSON: {e}')
    if obj(data).get('format') != fmt_name:
        raise BadInput(path, f'expected an object with "format": '
                       f'"{fmt_name}"')
    if data.get('version') != 1:
        raise BadInput(path, f'unsupported version {data.get("version")!r} '
                       '(expected 1)')
    return data


def save(fig, outdir, name, written):
    """Write fig as outdir/name.{png,svg,pdf}; returns the PNG's path."""
    for ext, meta in META.items():
        path = os.path.join(outdir, f'{name}.{ext}')
        fig.savefig(path, dpi=150 if ext == 'png' else 72, metadata=meta,
                    bbox_inches='tight', pad_inches=0.05)
        written.append(path)
    plt.close(fig)
    return written[-3]


def method_colors(names):
    """A stable colour per method, in order of first appearance; 'none' is
    grey."""
    palette = [c for i, c in enumerate(plt.get_cmap('tab10').colors)
               if i != 7] + list(plt.get_cmap('Dark2').colors)
    colors = {'none': (0.5, 0.5, 0.5)}
    for m in names:
        colors.setdefault(m, palette[(len(colors) - 1) % len(palette)])
    return colors


def contour_lines(ax, X, Y, z, levels, label_fmt):
    """Labelled black contour lines at the levels inside z's range."""
    inner = [v for v in levels if z.count() and z.min() < v < z.max()]
    if inner:
        cs = ax.contour(X, Y, z, levels=inner, colors='k', linewidths=0.6)
        ax.clabel(cs, fontsize=7, fmt=label_fmt)


# ---------------------------------------------------------------- report ---

def inside(out, rel, src, ctx):
    """The path of a file named in the JSON, checked to lie inside OUT."""
    if not isinstance(rel, str) or not rel:
        raise BadInput(src, f'{ctx}: expected a relative path, got {rel!r}')
    if os.path.isabs(rel) or re.match(r'^[A-Za-z]:', rel) or \
            '..' in re.split(r'[\\/]', rel):
        raise BadInput(src, f'{ctx}: path {rel!r} must be relative and '
                       'inside the output folder (no absolute path, no "..")')
    path = os.path.join(out, rel)
    if not os.path.realpath(path).startswith(os.path.realpath(out) + os.sep):
        raise BadInput(src, f'{ctx}: path {rel!r} leaves the output folder')
    return path


def data_uri(path, src, ctx):
    try:
        with open(path, 'rb') as f:
            data = f.read()
    except OSError as e:
        raise BadInput(src, f'{ctx}: {path}: {e.strerror or e}')
    if not data.startswith(b'\x89PNG\r\n\x1a\n'):
        raise BadInput(src, f'{ctx}: {path}: not a PNG file')
    return 'data:image/png;base64,' + base64.b64encode(data).decode('ascii')


def profile_xy(p):
    """(theta bin centres, values) of the bins that hold samples, or None."""
    b, v = num(obj(p).get('bin_degrees')), farray(obj(p).get('value'))
    c = farray(obj(p).get('count'))
    ok = np.isfinite(v) & ((c > 0) if c.size == v.size else True)
    if not (b > 0 and ok.any()):
        return None
    return ((np.arange(v.size) + 0.5) * b)[ok], v[ok]


def get_metric(comp, metric):
    """comp's value at a dotted path such as 'profile.rmse_terminator'."""
    for key in metric.split('.'):
        comp = obj(comp).get(key)
    return num(comp)


def column(r):
    """The image-grid column of a render."""
    rep, meth = str(r.get('representation')), str(r.get('method'))
    return GROUND_TRUTH if rep == 'displacement' else (
        meth if rep == 'bump' else f'{meth} ({rep})')


def fig_ranking(rk, colors, figdir, written):
    overall, scenes = objs(rk.get('overall')), objs(rk.get('per_scene'))
    if not overall and not any(objs(s.get('methods')) for s in scenes):
        return None
    methods = list(dict.fromkeys(str(e.get('method')) for e in overall + [
        e for s in scenes for e in objs(s.get('methods'))]))
    n = max(len(methods), 1)
    fig, (ax, ag) = plt.subplots(1, 2, figsize=(11, 1.2 + 0.35 * max(
        n, len(scenes) * n * 0.6)), layout='constrained')
    vals = [num(e.get('mean')) for e in overall]
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
        bars = [(i + (j - (n - 1) / 2) * h, num(e.get('mean')))
                for i, s in enumerate(scenes) for e in objs(s.get('methods'))
                if str(e.get('method')) == m and math.isfinite(
                    num(e.get('mean')))]
        ag.barh([b[0] for b in bars], [b[1] for b in bars], height=h,
                color=colors[m], label=m)
    ag.set_yticks(range(len(scenes)), [str(s.get('scene')) for s in scenes])
    ag.set_title('per scene')
    if methods:
        ag.legend(title='method', loc='lower right')
    for a in (ax, ag):
        a.invert_yaxis()
        a.set_xlabel(metric_label(rk.get('metric',
                                         'profile.rmse_terminator')))
    return save(fig, figdir, 'ranking', written)


def fig_profiles(var, colors, region, figdir, written):
    """L(theta) of every render of a variant, and its error vs the truth;
    empty bins are bridged (dots mark the bins when they are sparse)."""
    renders = objs(var.get('renders'))
    gt = next((profile_xy(r.get('profile')) for r in renders
               if r.get('renderer') == REF and
               r.get('representation') == 'displacement'), None)
    others = sorted({str(r.get('renderer')) for r in renders} - {REF})
    dashes = [(0, (5, 2)), (0, (2, 1.5)), (0, (6, 2, 1, 2)), (0, (1, 1))]
    fig, (ax, ad) = plt.subplots(2, 1, figsize=(9.5, 7), sharex=True,
                                 height_ratios=[3, 2], layout='constrained')
    finite = []
    for r in renders:
        xy = profile_xy(r.get('profile'))
        if xy is None:
            continue
        rend, meth, lab = str(r.get('renderer')), str(r.get('method')), \
            column(r)
        is_gt = lab == GROUND_TRUTH
        if rend == REF:
            style = dict(color='k', lw=2.8, zorder=5) if is_gt else dict(
                color=colors[meth], lw=1.4)
        else:
            style = dict(color='0.35' if is_gt else colors[meth], lw=1.2,
                         ls=dashes[others.index(rend) % len(dashes)])
            lab = f'{rend}: {lab}'
        span = (xy[0][-1] - xy[0][0]) / num(r['profile']['bin_degrees'])
        if xy[0].size < 0.6 * span:  # sparse: mark the bins
            style.update(marker='.', ms=4)
        ax.plot(*xy, label=lab, **style)
        finite.append(xy[0])
        if gt is not None and not (is_gt and rend == REF):
            ref = np.interp(xy[0], *gt, left=math.nan, right=math.nan)
            ad.plot(xy[0], xy[1] - ref, label=lab, **style)
    for a in (ax, ad):
        a.axvspan(*region, color='0.9', zorder=0, label='terminator region '
                  f'{region[0]:g}–{region[1]:g}°' if a is ax else None)
        a.grid(alpha=0.3)
    ad.axhline(0, color='k', lw=0.8)
    if finite:  # clip to the bins that hold samples
        finite = np.concatenate(finite)
        ad.set_xlim(max(0, finite.min() - 1), min(180, finite.max() + 1))
    ax.set_ylabel(L_LABEL)
    ad.set_ylabel(f'Δ{L_LABEL}: method − truth')
    ad.set_xlabel('θ: angle between light and base normal (degrees)')
    ax.set_title(f'terminator profiles: {var.get("label", var.get("id"))}',
                 wrap=True)
    ad.set_title(f'difference from the {REF} displacement ground truth'
                 if gt is not None else 'no evaluator ground truth')
    ax.legend(loc='upper left', bbox_to_anchor=(1.01, 1.0))
    return save(fig, figdir, f'profiles-{stem(var.get("id"))}', written)


def axis_text(v, i):
    """A tick label: numbers as they are, vectors as '#i: (x, y, z)'."""
    if isinstance(v, list):
        return f'#{i}: (' + ', '.join(fmt(t) for t in v) + ')'
    return fmt(v, digits=4) if math.isfinite(num(v)) else str(v)


def axis_index(values, v):
    def same(a, b):
        if isinstance(a, list) and isinstance(b, list):
            return len(a) == len(b) and all(map(same, a, b))
        fa, fb = num(a), num(b)
        if math.isfinite(fa) and math.isfinite(fb):
            return math.isclose(fa, fb, rel_tol=1e-9, abs_tol=1e-12)
        return a == b
    return next((i for i, a in enumerate(values) if same(a, v)), None)


def geometric(v):
    """Whether positive values are more evenly spaced on a log scale."""
    v = np.sort(np.asarray(v, dtype=float))
    if v.size < 3 or v[0] <= 0:
        return False

    def cv(d):
        return np.std(d) / np.mean(d) if np.mean(d) > 0 else math.inf
    return cv(np.diff(np.log(v))) < cv(np.diff(v))


def draw_grid(ax, grid, xs, ys, labels, kind, lim, title):
    """One panel: contour when kind == 'contour', else annotated heatmap;
    colours span lim = (vmin, vmax)."""
    cmap, norm = plt.get_cmap('viridis'), plt.Normalize(*lim)  # own norm:
    # one shared by several figures breaks matplotlib 3.6 at close
    xt, yt = ([axis_text(v, i) for i, v in enumerate(a)] for a in (xs, ys))
    if kind == 'contour':
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


def fig_plots(k, plot, doc, src, figdir, written):
    """Per scene, the metric over axes[x] x axes[y] (mean over the other
    axes): small multiples plot-<k>-<scene>.* and one file per method."""
    axes = objs(doc.get('axes'))
    x, y = plot.get('x'), plot.get('y')
    if x == y or not all(type(i) is int and 0 <= i < len(axes)
                         for i in (x, y)):
        raise BadInput(src, f'plots[{k}]: x and y must be two different '
                       f'indices into axes (0..{len(axes) - 1}), got {x!r}, '
                       f'{y!r}')
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    xs, ys = axes[x]['values'], axes[y]['values']
    variants = {v.get('id'): v for v in objs(doc.get('variants'))}
    cells = {}  # (scene, method) -> [sum grid, count grid]
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
    numeric = all(len(v) >= 2 and all(math.isfinite(num(t)) for t in v)
                  for v in (xs, ys))
    ox, oy = (np.argsort([num(t) for t in v]) if numeric
              else np.arange(len(v)) for v in (xs, ys))
    xs, ys = [xs[i] for i in ox], [ys[i] for i in oy]
    labels = [str(axes[i].get('label', axes[i].get('pointer')))
              for i in (x, y)]
    out = []
    for scene in dict.fromkeys(s for s, _ in cells):
        with np.errstate(invalid='ignore', divide='ignore'):
            grids = {m: (a[0] / a[1])[np.ix_(oy, ox)]
                     for (s, m), a in cells.items() if s == scene}
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
        for a, (m, g) in zip(axs.flat, grids.items()):
            im = draw_grid(a, g, xs, ys, labels, kind, lim, m)
            f1, a1 = plt.subplots(figsize=(5.4, 4.4), layout='constrained')
            f1.colorbar(draw_grid(a1, g, xs, ys, labels, kind, lim,
                                  f'{m}: {note}'),
                        ax=a1, label=metric_label(metric))
            save(f1, figdir, f'plot-{k}-{stem(scene)}-{stem(metric)}-'
                 f'{stem(m)}', written)
        fig.colorbar(im, ax=axs.ravel().tolist(), label=metric_label(metric))
        fig.suptitle(f'{metric_label(metric)}: {note} (mean over other axes)')
        out.append((scene, save(fig, figdir, f'plot-{k}-{stem(scene)}',
                                written)))
    return metric, rend, out


CSS = """body{font:15px/1.45 system-ui,sans-serif;max-width:1400px;
margin:1em auto;padding:0 1em;color:#222}h2{border-bottom:2px solid #ddd;
margin-top:2em}table{border-collapse:collapse;margin:.5em 0 1em}
td,th{border:1px solid #ccc;padding:3px 7px;vertical-align:top}
th{background:#f3f3f3}td.n{text-align:right;font-variant-numeric:
tabular-nums}.na{color:#999}img{max-width:100%}.fail td,.fail{color:#b00}
.grid img{width:160px;max-width:none;image-rendering:pixelated}
.scroll{overflow-x:auto}figure{margin:0}
figcaption{font-size:12px;color:#555}footer{margin-top:3em;border-top:1px
solid #ddd;font-size:13px;color:#555}nav a{margin-right:1em}"""


def table(head, rows, cls=''):
    """An HTML table of raw strings (escaped here) and numbers formatted by
    fmt (right-aligned); a number given as (value, scale) is scaled."""
    def td(c):
        if isinstance(c, str) or type(c) is int:
            return f'<td{" class=n" * (type(c) is int)}>{esc(c)}</td>'
        t = fmt(*c) if isinstance(c, tuple) else fmt(c)
        return f'<td class="n{" na" * (t == "n/a")}">{t}</td>'
    return ('<table><tr>' + ''.join(f'<th>{esc(c)}</th>' for c in head) +
            '</tr>' + ''.join(f'\n<tr{cls}>' + ''.join(map(td, r)) + '</tr>'
                              for r in rows) + '</table>')


def img(uri, alt, cap=''):
    c = f'<figcaption>{esc(cap)}</figcaption>' if cap else ''
    return f'<figure><img src="{uri}" alt="{esc(alt)}">{c}</figure>'


def image_grid(var, uris, missing, renderers):
    """Rows: renderers (image row, then difference row); columns: ground
    truth, then methods (Chiang 2019, Fig. 4)."""
    renders = objs(var.get('renders'))
    cols = list(dict.fromkeys([GROUND_TRUTH] + [column(r) for r in renders]))
    at = {(str(r.get('renderer')), column(r)): r for r in renders}

    def cell(rel, alt, cap):
        return '<td>' + (img(uris[rel], alt, cap) if rel is not None
                         else '') + '</td>'
    grid = '<tr><th>renderer</th>' + ''.join(f'<th>{esc(c)}</th>'
                                             for c in cols) + '</tr>'
    for rend in dict.fromkeys(renderers + [k[0] for k in at]):
        rs = [at.get((rend, c)) for c in cols]
        if not any(rs):
            continue
        grid += f'\n<tr><th>{esc(rend)}</th>' + ''.join(
            cell(r.get('image'), f'{rend} {c}', f'{rend} / {c}') if r else
            f'<td class="na">{esc(missing.get((rend, c), "not rendered"))}'
            '</td>' for c, r in zip(cols, rs)) + '</tr>'
        if any(r and r.get('difference') is not None for r in rs):
            grid += '\n<tr><th>difference</th>' + ''.join(
                cell(r.get('difference'), f'{rend} {c} difference',
                     f'{c} − displacement ({rend})') if r else '<td></td>'
                for c, r in zip(cols, rs)) + '</tr>'
    return f'<div class="scroll"><table class="grid">{grid}</table></div>'


def variant_html(var, uris, comps, missing, fig, renderers):
    vid = str(var.get('id'))
    metrics = [('profile.rmse_terminator', 100), ('profile.rmse_overall', 100),
               ('profile.max_error_terminator', 100),
               ('profile.max_step', 100), ('profile.position_error_deg', 1),
               ('profile.width_deg', 1), ('profile.lit_bias', 100),
               ('image.rmse', 1), ('image.ssim', 1)]
    rows = [[str(c.get('renderer')), str(c.get('method')),
             str(c.get('reference'))] +
            [(get_metric(c, m), s) for m, s in metrics] for c in comps]
    head = ['renderer', 'method', 'reference', 'terminator RMSE (%)',
            'overall RMSE (%)', 'max error (%)', 'max step (%)',
            'position error (deg)', 'width (deg)', 'lit bias (%)',
            'image RMSE (W m⁻² sr⁻¹)', 'SSIM']
    return (f'<h2 id="v-{esc(stem(vid))}">{esc(vid)}: '
            f'{esc(var.get("label", ""))}</h2>\n<h3>Images</h3>\n' +
            image_grid(var, uris, missing, renderers) +
            '\n<p class="note">Difference images: method minus the same '
            "renderer's displacement ground truth; red brighter, blue "
            'darker, white equal, saturating at ±0.25 albedo·E/π; grey '
            'where either image has no object.</p>' +
            '\n<h3>Terminator profiles</h3>\n' +
            img(data_uri(fig, fig, 'figure'), f'profiles {vid}',
                f'figures/profiles-{stem(vid)}.{{png,svg,pdf}}') +
            '\n<h3>Metrics</h3>\n' + (table(head, rows) if rows else
                                      '<p class="na">no comparisons</p>'))


def run_report(out):
    src = os.path.join(out, 'report.json')
    doc = load_json(src, 'penumbra-report')
    for key in ('axes', 'renderers', 'variants', 'comparisons', 'missing',
                'failures', 'plots'):
        if not isinstance(doc.get(key, []), list):
            raise BadInput(src, f'"{key}" must be an array')
    for i, a in enumerate(doc.get('axes', [])):
        if not isinstance(obj(a).get('values'), list):
            raise BadInput(src, f'axes[{i}]: expected {{"values": [...]}}')
    rends, rk = objs(doc.get('renderers')), obj(doc.get('ranking'))
    variants, comps = objs(doc.get('variants')), objs(doc.get('comparisons'))
    uris = {}  # the images named in the JSON, checked before any drawing
    for v in variants:
        for r in objs(v.get('renders')):
            for key in ('image', 'difference'):
                ctx = f'variant {v.get("id")}: {key}'
                if r.get(key) is not None:
                    path = inside(out, r[key], src, ctx)
                    uris[r[key]] = data_uri(path, src, ctx)
    lp = doc.get('lowpoly')  # checked before any drawing too
    lp = None if lp is None else LowPoly(lp, out, src)
    units = obj(doc.get('units'))
    terminator, lit = ([float(t) for t in r] if isinstance(r, list) and len(
        r) == 2 and all(math.isfinite(num(t)) for t in r) else d for r, d in (
        (units.get('terminator_region_deg'), [60.0, 100.0]),
        (units.get('lit_region_deg'), [0.0, 60.0])))
    figdir, written = os.path.join(out, 'figures'), []
    os.makedirs(figdir, exist_ok=True)
    groups = [('overall', objs(rk.get('overall')))] + [
        (f'scene {s.get("scene")}', objs(s.get('methods')))
        for s in objs(rk.get('per_scene'))]
    colors = method_colors(
        [str(m) for r in rends for m in r.get('methods') or []] +
        [str(e.get('method')) for _, g in groups for e in g] +
        [str(r.get('method')) for v in variants
         for r in objs(v.get('renders'))] +
        [str(c.get('method')) for c in comps])
    study = obj(doc.get('study'))
    title = f'Penumbra report: {study.get("name", "study")}'
    nav = ''.join(f'<a href="#v-{esc(stem(v.get("id")))}">{esc(v.get("id"))}'
                  '</a>' for v in variants)
    parts = [f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
             f'<meta name="viewport" content="width=device-width">'
             f'<title>{esc(title)}</title><style>{CSS}</style></head><body>'
             f'<h1>{esc(title)}</h1><p>Study <b>{esc(study.get("name", ""))}'
             f'</b> ({esc(study.get("file", ""))}), penumbra '
             f'{esc(doc.get("penumbra", "?"))}.</p><nav><a href="#headline">'
             f'Headline</a><a href="#renderers">Renderers</a>{nav}'
             '<a href="#plots">Sweeps</a>' +
             ('<a href="#lowpoly">Low-poly</a>' if lp else '') + '</nav>',
             '<h2 id="headline">Headline</h2>',
             f'<p>Ranking by {esc(rk.get("metric", "?"))} of renderer '
             f'{esc(rk.get("renderer", "?"))} against '
             f'{esc(rk.get("reference", "?"))}; lower is better.</p>']
    if not variants:
        parts.append('<p class="na">This study has no bump-mapping variants'
                     + (': see the low-poly section.' if lp else '.') +
                     '</p>')
    name, unit = METRICS.get(rk.get('metric'), (rk.get('metric'), ''))
    scale = 100 if unit == FRACTION else 1
    for group, entries in groups:
        if entries:
            parts.append(f'<h3>{esc(group)}</h3>' + table(
                ['method', f'mean {name} ({"%" if scale == 100 else unit})',
                 'rank', 'count'],
                [[str(e.get('method')), (e.get('mean'), scale),
                  i + 1 if math.isfinite(num(e.get('mean'))) else None,
                  e.get('count')] for i, e in enumerate(entries)]))
    fig = fig_ranking(rk, colors, figdir, written)
    if fig:
        parts.append(img(data_uri(fig, fig, 'figure'), 'ranking',
                         'figures/ranking.{png,svg,pdf}'))
    parts.append('<h2 id="renderers">Renderers</h2>' + table(
        ['renderer', 'version', 'methods', 'note'],
        [[str(r.get('id')), str(r.get('version', '')),
          ', '.join(map(str, r.get('methods') or [])),
          str(r.get('note', ''))] for r in rends]))
    miss = objs(doc.get('missing'))
    if miss:
        parts.append('<h3>Rows a renderer cannot provide</h3>' + table(
            ['renderer', 'method', 'why'],
            [[str(m.get(k, '')) for k in ('renderer', 'method', 'why')]
             for m in miss]))
    fails = objs(doc.get('failures'))
    if fails:
        parts.append('<h3 class="fail">Failures</h3>' + table(
            ['render', 'error'], [[str(f.get('render', '')),
                                   str(f.get('error', ''))] for f in fails],
            ' class="fail"'))
    missing = {(str(m.get('renderer')), str(m.get('method'))):
               str(m.get('why', '')) for m in miss}
    for v in variants:
        fig = fig_profiles(v, colors, terminator, figdir, written)
        parts.append(variant_html(
            v, uris, [c for c in comps if c.get('variant') == v.get('id')],
            missing, fig, [str(r.get('id')) for r in rends]))
    parts.append('<h2 id="plots">Sweeps</h2>')
    for k, plot in enumerate(doc.get('plots', [])):
        if not isinstance(plot, dict):
            raise BadInput(src, f'plots[{k}] must be an object')
        metric, rend, figs = fig_plots(k, plot, doc, src, figdir, written)
        parts.append(f'<h3>{esc(metric_label(metric))}, {esc(rend)}</h3>')
        parts += [img(data_uri(f, f, 'figure'), f'plot {k} {s}',
                      f'scene {s}: {os.path.relpath(f, out)[:-4]}'
                      '.{png,svg,pdf}') for s, f in figs] or [
            '<p class="na">no finite values for this plot</p>']
    if not doc.get('plots'):
        parts.append('<p class="na">no sweeps in this study</p>')
    if lp:
        parts += lowpoly_html(lp, out, src, figdir, written)
    parts.append(
        '<footer><p>Profile values are fractions of albedo·E/π (a smooth '
        'Lambertian surface gives cos θ). θ is the angle between the light '
        'direction and the base-surface normal, in degrees; the terminator '
        f'region is {terminator[0]:g}–{terminator[1]:g}°, the lit region '
        f'{lit[0]:g}–{lit[1]:g}°. Profile RMSE, errors, '
        'steps and bias in the tables are in percent of albedo·E/π; image '
        'metrics are in the image unit (' +
        esc(units.get('image', 'W m^-2 sr^-1')) +
        '). ' + ('In the low-poly section the darkened and lost-shadow '
                 'fractions are percent of pixels, max darkening and the '
                 'terminator RMSE percent of albedo·E/π, shadow shifts '
                 'pixels. ' if lp else '') +
        'Every figure is also in figures/ as PNG, SVG and PDF.</p>'
        '</footer></body></html>\n')
    path = os.path.join(out, 'report.html')
    with open(path + '.tmp', 'w', encoding='utf-8') as f:
        f.write('\n'.join(parts))
    os.replace(path + '.tmp', path)
    return written + [path]


# -------------------------------------------------------------- low-poly ---

LP_TRUTH = 'analytic'             # the untessellated surface
LP_PANELS = (                     # (metric, name, unit, scale)
    ('shadow.darkened_fraction', 'darkened fraction', '% of the lit pixels',
     100),
    ('shadow.max_darkening', 'max darkening', '% of albedo·E/π', 100),
    ('profile.rmse_terminator', 'terminator profile RMSE',
     '% of albedo·E/π', 100))
LP_SIDE = (
    ('shadow.lost_shadow_fraction', 'lost cast shadow',
     '% of the analytic shadow', 100),
    ('shadow.shadow_shift_px', 'cast-shadow shift', 'pixels', 1),
    ('shadow.darkened_fraction', 'darkened fraction', '% of the lit pixels',
     100))
LP_UNITS = ('darkened_fraction', 'max_darkening', 'lost_shadow_fraction',
            'shadow_shift_px')
MARKERS = 'osD^vPX*<>p'
RENDERER_DASHES = ['-', (0, (5, 2)), (0, (6, 2, 1, 2)), (0, (2, 1.5))]


class LowPoly:
    """report['lowpoly'] checked, with every variant and comparison placed in
    a group (the scene and the values of the non-convergence axes) at a
    level (the convergence axis' value)."""

    def __init__(self, lp, out, src):
        if not isinstance(lp, dict):
            raise BadInput(src, '"lowpoly" must be an object or null')
        for key in ('axes', 'renderers', 'variants', 'comparisons',
                    'missing'):
            if not isinstance(lp.get(key, []), list):
                raise BadInput(src, f'lowpoly: "{key}" must be an array')
        self.axes = objs(lp.get('axes'))
        for i, a in enumerate(self.axes):
            if not isinstance(a.get('values'), list):
                raise BadInput(src, f'lowpoly: axes[{i}]: expected '
                               '{"values": [...]}')
        ptr = lp.get('convergence_axis')
        self.conv = next((i for i, a in enumerate(self.axes)
                          if ptr is not None and a.get('pointer') == ptr),
                         0 if len(self.axes) == 1 else None)  # the only one
        self.variants = objs(lp.get('variants'))
        self.comps = objs(lp.get('comparisons'))
        self.renderers = objs(lp.get('renderers'))
        self.missing = list({json.dumps(m, sort_keys=True): m for m in objs(
            lp.get('missing'))}.values())  # once per variant: once here
        self.ranking = obj(lp.get('ranking'))
        self.units = obj(lp.get('units'))
        for v in self.variants:  # every image path, before any drawing
            for r in objs(v.get('renders')):
                for key in ('image', 'difference'):
                    if r.get(key) is not None:
                        inside(out, r[key], src,
                               f'lowpoly variant {v.get("id")}: {key}')
        if self.conv is not None:
            vals = self.axes[self.conv]['values']
            self.numeric = bool(vals) and all(
                math.isfinite(num(t)) for t in vals)
            self.levels = sorted(vals, key=num) if self.numeric else \
                list(vals)
            self.xlabel = str(self.axes[self.conv].get(
                'label', self.axes[self.conv].get('pointer')))
        else:  # no convergence axis: the variants' axis values as text
            self.numeric = False
            self.levels = list(dict.fromkeys(
                self.place(v)[1] for v in self.variants + self.comps))
            self.xlabel = 'variant'
        self.groups = list(dict.fromkeys(
            self.place(x)[0] for x in self.variants + self.comps))
        self.rend_ids = list(dict.fromkeys(
            [str(r.get('id')) for r in self.renderers] +
            [str(c.get('renderer')) for c in self.comps]))
        self.offsets = list(dict.fromkeys(
            [str(o) for r in self.renderers for o in r.get('offsets') or []] +
            [str(c.get('offset')) for c in self.comps]))
        self.colors = method_colors(self.offsets)

    def place(self, x):
        """(group, level) of a variant or comparison; level None when its
        axis values do not fit the axes."""
        av, scene = x.get('axis_values'), str(x.get('scene'))
        if not isinstance(av, list) or len(av) != len(self.axes):
            return scene, None
        if self.conv is None:
            return scene, ', '.join(axis_text(v, i)
                                    for i, v in enumerate(av)) or '—'
        return scene + ''.join(
            f', {a.get("label", a.get("pointer"))}={axis_text(v, i)}'
            for i, (a, v) in enumerate(zip(self.axes, av))
            if i != self.conv), av[self.conv]

    def level_index(self, x):
        level = self.place(x)[1]
        if self.conv is None:
            return self.levels.index(level) if level in self.levels else None
        return None if level is None else axis_index(self.levels, level)

    def level_text(self, level):
        return axis_text(level, 0) if self.conv is not None else str(level)

    def series(self, group, own):
        """{(renderer, offset): {metric: array over levels}} of the group's
        comparisons: own=False the evaluator against evaluator:analytic,
        own=True the other renderers against their own analytic render."""
        acc = {}
        for c in self.comps:
            rend = str(c.get('renderer'))
            if (rend != REF) != own or \
                    c.get('reference') != f'{rend}:{LP_TRUTH}' or \
                    self.place(c)[0] != group:
                continue
            j = self.level_index(c)
            if j is None:
                continue
            key = (rend, str(c.get('offset')))
            s = acc.setdefault(key, {})
            for metric, *_ in LP_PANELS + LP_SIDE:
                a = s.setdefault(metric, np.zeros((2, len(self.levels))))
                v = get_metric(c, metric)
                if math.isfinite(v):
                    a[:, j] += (v, 1)
        order = {o: i for i, o in enumerate(self.offsets)}
        rorder = {r: i for i, r in enumerate(self.rend_ids)}
        out = {}
        for key in sorted(acc, key=lambda k: (rorder.get(k[0], 0),
                                              order.get(k[1], 0))):
            with np.errstate(invalid='ignore', divide='ignore'):
                out[key] = {m: a[0] / a[1] for m, a in acc[key].items()}
        return out

    def cast_shadow_pixels(self, group):
        """The reference cast-shadow pixel counts of a group's
        comparisons (empty when the scene casts no shadow)."""
        return sorted({int(get_metric(c, 'shadow.shadowed_pixels'))
                       for c in self.comps if self.place(c)[0] == group and
                       get_metric(c, 'shadow.shadowed_pixels') > 0})


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


def fig_lp_lines(name, title, lp, series, panels, style, figdir, written):
    """One panel per metric over the levels, one line per series; returns
    (png path, [(panel name, log y?, zeros on a floor?)])."""
    levels = lp.levels
    xs = np.array([num(t) for t in levels]) if lp.numeric else \
        np.arange(len(levels), dtype=float)
    log2 = lp.numeric and len(levels) >= 2 and (xs > 0).all()
    fig, axs = plt.subplots(1, len(panels), squeeze=False,
                            layout='constrained',
                            figsize=(4.3 * len(panels) + 2.4, 4.1))
    floors = []
    for ax, (metric, pname, unit, scale) in zip(axs[0], panels):
        ys = {k: s[metric] * scale for k, s in series.items()}
        floor = log_floor(ax, np.concatenate(list(ys.values()) or [[]]))
        for i, (key, y) in enumerate(ys.items()):
            if floor is not None:
                y = np.where(y == 0, floor, y)
            ax.plot(xs, y, label=style(key)[0], **style(key)[1], zorder=2 + i,
                    marker=MARKERS[i % len(MARKERS)], mfc='none', mew=1.2,
                    ms=max(3.0, 9 - 0.9 * i), lw=max(0.8, 2.6 - 0.3 * i))
        floors.append((pname, ax.get_yscale() == 'log', floor is not None))
        if floor is not None:
            ax.axhline(floor, color='0.55', lw=0.8, ls=':', zorder=1)
            ax.text(0.98, floor / 1.15, 'zero: drawn on this floor',
                    fontsize=7, color='0.4', ha='right', va='top',
                    transform=ax.get_yaxis_transform())
            ax.set_ylim(bottom=floor / 3)
        if log2:
            ax.set_xscale('log', base=2)
        ax.set_xticks(xs, [lp.level_text(t) for t in levels],
                      rotation=45 if len(levels) > 8 else 0)
        ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        ax.set(title=pname, xlabel=lp.xlabel, ylabel=f'{pname} ({unit})')
        ax.grid(alpha=0.3)
    axs[0][-1].legend(loc='upper left', bbox_to_anchor=(1.02, 1.0))
    fig.suptitle(title)
    return save(fig, figdir, name, written), floors


def lp_style(lp, own):
    """(label, line style) of a series: colour by offset, dashes by
    renderer for the external renderers."""
    def style(key):
        rend, off = key
        if not own:
            return off, dict(color=lp.colors[off])
        ext = [r for r in lp.rend_ids if r != REF]
        dash = RENDERER_DASHES[ext.index(rend) % len(RENDERER_DASHES)] \
            if rend in ext else '-'
        return f'{rend}: {off}', dict(color=lp.colors[off], ls=dash)
    return style


def lp_caption(path, out, floors, lp):
    cap = f'figures/{os.path.basename(path)[:-4]}.{{png,svg,pdf}}. '
    if lp.numeric and len(lp.levels) >= 2 and all(
            num(t) > 0 for t in lp.levels):
        cap += f'x: {lp.xlabel}, log₂ axis. '
    logs = [n for n, log, _ in floors if log]
    zeros = [n for n, _, zero in floors if zero]
    if logs:
        cap += 'Log y axis (' + ', '.join(logs) + ')'
        cap += ('; values of exactly 0 are drawn on the dotted floor line '
                '(' + ', '.join(zeros) + '). ') if zeros else '. '
    return cap + ('Offsets with equal values overlap: larger hollow markers '
                  'and thicker lines lie under smaller ones.')


def lp_rank_table(entries):
    vals = [num(e.get('darkened_fraction')) for e in entries]
    rows = []
    for e, v in zip(entries, vals):
        rank = 1 + sum(w < v for w in vals if math.isfinite(w)) \
            if math.isfinite(v) else None  # equal values share a rank
        rows.append([rank, str(e.get('offset')), (v, 100),
                     (e.get('rmse_terminator'), 100), e.get('count')])
    return table(['rank', 'offset', 'mean darkened fraction (% of lit '
                  'pixels)', 'mean terminator profile RMSE (% of '
                  'albedo·E/π)', 'count'], rows)


def lp_grid(lp, var, uris):
    """Columns: the analytic truth, then each offset; rows: per renderer
    its images, then their differences from its analytic render."""
    renders = objs(var.get('renders'))
    at = {(str(r.get('renderer')), str(r.get('offset'))): r for r in renders}
    cols = list(dict.fromkeys([LP_TRUTH] + [
        o for o in lp.offsets if any(k[1] == o for k in at)] +
        [k[1] for k in at]))
    why = {(str(m.get('renderer')), str(m.get('offset'))): str(m.get('why'))
           for m in lp.missing if 'offset' in m}

    def cell(rel, alt, cap):
        return '<td>' + img(uris[rel], alt, cap) + '</td>'

    def tri(r):
        t = num(r.get('triangles'))
        return f', {t:.0f} triangles' if math.isfinite(t) else ''
    grid = '<tr><th>renderer</th>' + ''.join(
        f'<th>{esc("analytic surface (truth)" if c == LP_TRUTH else c)}</th>'
        for c in cols) + '</tr>'
    for rend in dict.fromkeys(lp.rend_ids + [k[0] for k in at]):
        rs = [at.get((rend, c)) for c in cols]
        if not any(rs):
            continue
        grid += f'\n<tr><th>{esc(rend)}</th>' + ''.join(
            cell(r['image'], f'{rend} {c}', f'{rend} / {c}{tri(r)}')
            if r and r.get('image') is not None else
            f'<td class="na">{esc(why.get((rend, c), "not rendered"))}</td>'
            for c, r in zip(cols, rs)) + '</tr>'
        if any(r and r.get('difference') is not None for r in rs):
            grid += '\n<tr><th>difference</th>' + ''.join(
                cell(r['difference'], f'{rend} {c} difference',
                     f'{c} − analytic ({rend})')
                if r and r.get('difference') is not None else '<td></td>'
                for c, r in zip(cols, rs)) + '</tr>'
    return f'<div class="scroll"><table class="grid">{grid}</table></div>'


def lowpoly_html(lp, out, src, figdir, written):
    """The low-poly section's HTML parts."""
    parts = [
        '<h2 id="lowpoly">Low-poly meshes: the smooth-shading terminator</h2>',
        '<p>A smooth-shaded low-poly mesh shades each flat triangle with '
        'normals interpolated from its vertices, so near the terminator a '
        'point can be shaded as facing the light while the flat triangle it '
        'lies on, or its neighbours, block the shadow ray: the mesh shadows '
        'itself along a stair-stepped line that follows the facets. Each '
        'offset method moves the shadow ray’s origin off the triangle so '
        'that the ray clears the neighbouring facets (<i>none</i> leaves it '
        'on the triangle). The ground truth is the same scene with the '
        'analytic, untessellated surface. Moving the origin can also thin '
        'or move a cast shadow (another object’s, or the open cylinder’s '
        'own wall): that is measured below, not hidden.</p>']
    u = lp.units
    keys = [k for k in LP_UNITS if k in u] + sorted(
        k for k in u if k not in LP_UNITS)
    parts.append('<dl>' + ''.join(
        f'<dt><b>{esc(k)}</b></dt><dd>{esc(u[k])}</dd>' for k in keys) +
        '<dt><b>rmse_terminator</b></dt><dd>terminator-region profile RMSE '
        'against the analytic render’s profile, fraction of albedo·E/π '
        '(shown as %)</dd></dl>')
    rk = lp.ranking
    parts.append(f'<h3>Ranking</h3><p>Offsets of renderer '
                 f'{esc(rk.get("renderer", "?"))} against '
                 f'{esc(rk.get("reference", "?"))}, by '
                 f'{esc(rk.get("metric", "?"))} (mean over tessellation '
                 'levels; lower is better; equal values share a rank).</p>')
    for group, entries in [('overall', objs(rk.get('overall')))] + [
            (f'scene {s.get("scene")}', objs(s.get('offsets')))
            for s in objs(rk.get('per_scene'))]:
        parts.append(f'<h4>{esc(group)}</h4>' + (
            lp_rank_table(entries) if entries else
            '<p class="na">no comparisons</p>'))

    parts.append('<h3>Convergence over tessellation levels</h3>')
    if lp.conv is None or not lp.numeric:
        parts.append('<p class="na">No numeric convergence axis: the '
                     'metrics are plotted over the variants in order.</p>')
    shadow_groups = []
    for group in lp.groups:
        own = lp.series(group, False)
        ext = lp.series(group, True)
        if lp.cast_shadow_pixels(group):
            shadow_groups.append((group, own, ext))
        if not own and not ext:
            continue
        parts.append(f'<h4>{esc(group)}</h4>')
        if own:
            f, floors = fig_lp_lines(
                f'lowpoly-convergence-{stem(group)}',
                f'{group}: {REF} offsets vs {REF}:{LP_TRUTH}', lp, own,
                LP_PANELS, lp_style(lp, False), figdir, written)
            parts.append(img(data_uri(f, f, 'figure'),
                             f'convergence {group}',
                             lp_caption(f, out, floors, lp)))
        if ext:
            f, floors = fig_lp_lines(
                f'lowpoly-external-{stem(group)}',
                f'{group}: external renderers vs their own analytic render',
                lp, ext, LP_PANELS, lp_style(lp, True), figdir, written)
            parts.append(img(data_uri(f, f, 'figure'),
                             f'external renderers {group}',
                             lp_caption(f, out, floors, lp)))

    parts.append('<h3>Side effects on cast shadows</h3>')
    if not shadow_groups:
        parts.append('<p class="na">No scene of this study casts a shadow '
                     'in its analytic render.</p>')
    for group, own, ext in shadow_groups:
        px = lp.cast_shadow_pixels(group)
        parts.append(
            f'<h4>{esc(group)}</h4><p>The analytic render’s cast shadow '
            f'covers {px[0]}{f"–{px[-1]}" if len(px) > 1 else ""} pixels. '
            'Per offset and tessellation level, against the same renderer’s '
            'analytic render; n/a: no cast shadow in one of the two.</p>')
        rows = {**own, **ext}
        for metric, pname, unit, scale in LP_SIDE:
            parts.append(table(
                [f'{pname} ({unit}); offset \\ {lp.xlabel}'] +
                [lp.level_text(t) for t in lp.levels],
                [[k[1] if k[0] == REF else f'{k[0]}: {k[1]}'] +
                 [(v, scale) for v in s[metric]] for k, s in rows.items()]))
        f, floors = fig_lp_lines(
            f'lowpoly-shadow-{stem(group)}',
            f'{group}: cast-shadow side effects vs the analytic render', lp,
            rows, LP_SIDE[:2], lp_style(lp, bool(ext)), figdir, written)
        parts.append(img(data_uri(f, f, 'figure'), f'cast shadow {group}',
                         lp_caption(f, out, floors, lp)))

    parts.append(
        '<h3>Images: the stair-stepped terminator and how each method '
        'removes it</h3><p class="note">At the two coarsest tessellation '
        'levels. Difference images: offset minus the same renderer’s '
        'analytic render; red brighter, blue darker, white equal, '
        'saturating at ±0.25 albedo·E/π; grey where either image has no '
        'object.</p>')
    uris = {}
    scene_why = {}
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
            for r in objs(v.get('renders')):
                for key in ('image', 'difference'):
                    rel = r.get(key)
                    if rel is not None and rel not in uris:
                        ctx = f'lowpoly variant {v.get("id")}: {key}'
                        uris[rel] = data_uri(inside(out, rel, src, ctx),
                                             src, ctx)
            parts.append(f'<h4>{esc(v.get("id"))}: '
                         f'{esc(v.get("label", group))}</h4>' +
                         lp_grid(lp, v, uris))
            why = scene_why.get(str(v.get('scene')))
            if why:
                parts.append('<p class="na">Not rendered: ' +
                             esc('; '.join(why)) + '</p>')

    parts.append('<h3>Renderers and what they cannot provide</h3>' + table(
        ['renderer', 'offsets'],
        [[str(r.get('id')), ', '.join(map(str, r.get('offsets') or []))]
         for r in lp.renderers]))
    if lp.missing:
        parts.append(table(
            ['renderer', 'offset or scene', 'why'],
            [[str(m.get('renderer', '')),
              f'offset {m["offset"]}' if 'offset' in m else
              f'scene {m.get("scene", "")}', str(m.get('why', ''))]
             for m in lp.missing]))
    elif lp.renderers:
        parts.append('<p>Every renderer provides every offset and scene.</p>')

    parts.append('<h3>All comparisons</h3>' + (
        '' if lp.comps else '<p class="na">no comparisons</p>'))
    tris = {(str(v.get('id')), str(r.get('renderer')), str(r.get('offset'))):
            r.get('triangles') for v in lp.variants
            for r in objs(v.get('renders'))}
    head = ['renderer', 'offset', 'reference', lp.xlabel, 'triangles',
            'darkened (%)', 'max darkening (%)', 'terminator RMSE (%)',
            'lost shadow (%)', 'shadow shift (px)', 'position error (deg)',
            'image RMSE', 'SSIM']
    metrics = [('shadow.darkened_fraction', 100),
               ('shadow.max_darkening', 100),
               ('profile.rmse_terminator', 100),
               ('shadow.lost_shadow_fraction', 100),
               ('shadow.shadow_shift_px', 1),
               ('profile.position_error_deg', 1), ('image.rmse', 1),
               ('image.ssim', 1)]
    for group in lp.groups:
        cs = [c for c in lp.comps if lp.place(c)[0] == group]
        if not cs:
            continue
        rows = [[str(c.get('renderer')), str(c.get('offset')),
                 str(c.get('reference')),
                 lp.level_text(lp.place(c)[1]) if lp.place(c)[1] is not None
                 else 'n/a',
                 tris.get((str(c.get('variant')), str(c.get('renderer')),
                           str(c.get('offset'))))] +
                [(get_metric(c, m), s) for m, s in metrics] for c in cs]
        parts.append(f'<details><summary>{esc(group)}: {len(cs)} '
                     f'comparisons</summary>{table(head, rows)}</details>')
    return parts


# --------------------------------------------------------------- contour ---

def contour_panel(ax, L, D, G, title, diff=None):
    """G, or a difference when diff is given (its symmetric limit)."""
    if diff is None:
        levels, cmap, lines = np.linspace(0, 1, 11), 'viridis', None
    else:
        levels = MaxNLocator(20, symmetric=True).tick_values(-diff, diff)
        cmap = 'RdBu'
        lines = MaxNLocator(8, symmetric=True).tick_values(-diff, diff)
    z = np.ma.masked_invalid(G)
    if z.count():
        extend = 'both' if diff is None and (z.min() < 0 or z.max() > 1) \
            else 'neither'
        im = ax.contourf(L, D, z, levels=levels, cmap=cmap, extend=extend)
        contour_lines(ax, L, D, z, levels if lines is None else lines,
                      '%.2g')
    else:
        ax.text(0.5, 0.5, 'undefined everywhere', transform=ax.transAxes,
                ha='center')
        ax.set(xlim=(L[0], L[-1]), ylim=(D[0], D[-1]))
        im = plt.cm.ScalarMappable(plt.Normalize(levels[0], levels[-1]),
                                   cmap)
    lo, hi = max(L[0], D[0]), min(L[-1], D[-1])
    ax.plot([lo, hi], [lo, hi], '--', color='w', lw=1.3,
            label='y = x: shading normal points at the light',
            path_effects=[patheffects.withStroke(linewidth=2.6,
                                                 foreground='k')])
    ax.legend(loc='upper left', fontsize=7)
    ax.set(xlabel='light angle from Ng (degrees)', title=title,
           ylabel='shading-normal deviation towards the light (degrees)')
    return im


def run_contour(path, outdir):
    doc = load_json(path, 'penumbra-contour')
    L, D = farray(doc.get('light_deg')), farray(doc.get('deviation_deg'))
    for name, a in (('light_deg', L), ('deviation_deg', D)):
        if a.size < 2 or not np.all(np.diff(a) > 0):
            raise BadInput(path, f'"{name}": expected >= 2 increasing numbers')
    if not isinstance(doc.get('methods'), list) or not doc['methods']:
        raise BadInput(path, '"methods": expected a non-empty array')
    G = {}
    for i, m in enumerate(doc['methods']):
        g = obj(m).get('G')
        if not isinstance(obj(m).get('id'), str) or m['id'] in G or \
                not isinstance(g, list) or len(g) != D.size or \
                any(not isinstance(r, list) or len(r) != L.size for r in g):
            raise BadInput(path, f'methods[{i}]: expected {{"id": a new '
                           f'string, "G": {D.size} rows of {L.size} numbers}}')
        G[m['id']] = np.array([farray(r) for r in g])
    os.makedirs(outdir, exist_ok=True)
    written, ids = [], list(G)

    def diff_panel(ax, fig, a, b):
        d = G[a] - G[b]
        lim = np.nanmax(np.abs(d)) if np.isfinite(d).any() else 0
        im = contour_panel(ax, L, D, d, f'G[{a}] − G[{b}]\npositive: {a} '
                           'lets more light through', float(lim) or 1e-3)
        fig.colorbar(im, ax=ax, label=f'G[{a}] − G[{b}]')
    for m, g in G.items():
        fig, ax = plt.subplots(figsize=(5.6, 4.6), layout='constrained')
        im = contour_panel(ax, L, D, g, f'terminator factor G: {m}')
        fig.colorbar(im, ax=ax, label='G (fraction of light let through)')
        save(fig, outdir, f'contour-{stem(m)}', written)
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            fig, ax = plt.subplots(figsize=(5.6, 4.8), layout='constrained')
            diff_panel(ax, fig, a, b)
            save(fig, outdir, f'contour-diff-{stem(a)}-{stem(b)}', written)
    n = len(ids) + (len(ids) >= 2)
    fig, axs = plt.subplots(1, n, figsize=(4.3 * n + 1, 4.6),
                            layout='constrained', squeeze=False)
    for ax, m in zip(axs[0], ids):
        im = contour_panel(ax, L, D, G[m], m)
    fig.colorbar(im, ax=axs[0][:len(ids)].tolist(), label='G')
    if len(ids) >= 2:
        diff_panel(axs[0][-1], fig, ids[0], ids[1])
    save(fig, outdir, 'contour', written)
    return written


def main(argv):
    try:
        if len(argv) == 2 and argv[0] == 'report':
            written = run_report(argv[1])
        elif len(argv) == 3 and argv[0] == 'contour':
            written = run_contour(argv[1], argv[2])
        else:
            print('usage: report.py report OUT | '
                  'report.py contour CONTOUR.json OUTDIR', file=sys.stderr)
            return 2
    except BadInput as e:
        print(f'report.py: {e}', file=sys.stderr)
        return 2
    except OSError as e:
        print(f'report.py: {e.filename or "output"}: {e.strerror or e}',
              file=sys.stderr)
        return 1
    print('\n'.join(written))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
