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

report.json ("format": "penumbra-report", "version": 1; any number may be
null): penumbra, study{name,file}, units{}, axes[{pointer,label,values}],
renderers[{id,version,methods[],note}], variants[{id,scene,label,
axis_values[], renders[{renderer,representation,method,image,difference,
profile{bin_degrees,value[],count[]}}]}], comparisons[{variant,scene,
renderer,method,reference,profile{rmse_terminator,...},image{rmse,ssim,...}}],
ranking{metric,reference,renderer,per_scene[{scene,methods[{method,mean,
count}]}],overall[...]}, missing[{renderer,method,why}],
failures[{render,error}], plots[{metric,x,y,kind,renderer}]. image and
difference are paths relative to OUT (PNG).

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
META = {'png': {'Software': None},
        'svg': {'Date': None, 'Creator': None},
        'pdf': {'CreationDate': None, 'Creator': None, 'Producer': None}}
REF = 'evaluator'
PROFILE_UNIT = 'fraction of albedo·E/π'
L_LABEL = 'L / (albedo·E/π)'
THETA_LABEL = 'θ: angle between light and base normal (degrees)'
METRICS = {  # metric -> (name, unit)
    'profile.rmse_terminator': ('terminator-region profile RMSE', PROFILE_UNIT),
    'profile.rmse_overall': ('profile RMSE, all bins', PROFILE_UNIT),
    'profile.max_error_terminator': ('max terminator-region error',
                                     PROFILE_UNIT),
    'profile.max_step': ('largest profile step', PROFILE_UNIT),
    'profile.position_error_deg': ('terminator position error', 'degrees'),
    'profile.width_deg': ('terminator width', 'degrees'),
    'profile.lit_bias': ('lit-region bias', PROFILE_UNIT),
    'image.rmse': ('image RMSE', 'W m⁻² sr⁻¹'),
    'image.ssim': ('image SSIM', 'unitless'),
    'image.mask_iou': ('silhouette IoU', 'unitless')}


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
    if not isinstance(data, dict) or data.get('format') != fmt_name:
        raise BadInput(path, f'expected "format": "{fmt_name}"')
    if data.get('version') != 1:
        raise BadInput(path, f'unsupported version {data.get("version")!r} '
                       '(expected 1)')
    return data


def save(fig, outdir, name, written):
    """Write fig as outdir/name.{png,svg,pdf}, deterministically."""
    for ext, meta in META.items():
        path = os.path.join(outdir, f'{name}.{ext}')
        fig.savefig(path, dpi=150 if ext == 'png' else 72, metadata=meta,
                    bbox_inches='tight', pad_inches=0.05)
        written.append(path)
    plt.close(fig)
    return os.path.join(outdir, f'{name}.png')


def method_colors(names):
    """A stable colour per method; 'none' is grey."""
    palette = [c for i, c in enumerate(plt.get_cmap('tab10').colors)
               if i != 7] + list(plt.get_cmap('Dark2').colors)
    colors, k = {}, 0
    for m in names:
        if m not in colors:
            colors[m] = (0.5, 0.5, 0.5) if m == 'none' else \
                palette[k % len(palette)]
            k += m != 'none'
    return colors


# ---------------------------------------------------------------- report ---

def inside(out, rel, where):
    """The path of a file named in the JSON, checked to lie inside OUT.

    where is (file, context) for the error message."""
    if not isinstance(rel, str) or not rel:
        raise BadInput(where[0], f'{where[1]}: expected a relative path, '
                       f'got {rel!r}')
    parts = re.split(r'[\\/]', rel)
    if os.path.isabs(rel) or re.match(r'^[A-Za-z]:', rel) or '..' in parts:
        raise BadInput(where[0], f'{where[1]}: path {rel!r} must be relative '
                       'and inside the output folder (no absolute path, '
                       'no "..")')
    path = os.path.join(out, rel)
    if not os.path.realpath(path).startswith(os.path.realpath(out) + os.sep):
        raise BadInput(where[0], f'{where[1]}: path {rel!r} leaves the '
                       'output folder')
    return path


def data_uri(path, where):
    try:
        with open(path, 'rb') as f:
            data = f.read()
    except OSError as e:
        raise BadInput(where[0], f'{where[1]}: {path}: {e.strerror or e}')
    if not data.startswith(b'\x89PNG\r\n\x1a\n'):
        raise BadInput(where[0], f'{where[1]}: {path}: not a PNG file')
    return 'data:image/png;base64,' + base64.b64encode(data).decode('ascii')


def profile_xy(p):
    """(theta bin centres, values with empty bins as nan) or None."""
    if not isinstance(p, dict):
        return None
    b, v = num(p.get('bin_degrees')), farray(p.get('value'))
    if not (b > 0) or v.size == 0:
        return None
    c = farray(p.get('count'))
    if c.size == v.size:
        v[~(c > 0)] = math.nan
    return (np.arange(v.size) + 0.5) * b, v


def get_metric(comp, metric):
    node = comp
    for key in metric.split('.'):
        node = node.get(key) if isinstance(node, dict) else None
    return num(node)


def fig_ranking(rk, colors, figdir, written):
    overall = [e for e in rk.get('overall') or [] if isinstance(e, dict)]
    scenes = [s for s in rk.get('per_scene') or [] if isinstance(s, dict)]
    if not overall and not scenes:
        return None
    methods = list(dict.fromkeys(
        [str(e.get('method')) for e in overall] +
        [str(e.get('method')) for s in scenes for e in s.get('methods', [])]))
    n = len(methods)
    fig, axs = plt.subplots(1, 2, figsize=(11, 1.2 + 0.35 * max(
        n, len(scenes) * n * 0.6)), layout='constrained', squeeze=False)
    ax = axs[0][0]
    y = np.arange(len(overall))
    vals = [num(e.get('mean')) for e in overall]
    ax.barh(y, np.nan_to_num(vals), color=[colors[str(e.get('method'))]
                                           for e in overall])
    for yi, v in zip(y, vals):
        ax.text(v if math.isfinite(v) else 0, yi, ' ' + fmt(v), va='center',
                fontsize=8)
    ax.set_yticks(y, [str(e.get('method')) for e in overall])
    ax.invert_yaxis()
    ax.set_xlabel(f'terminator-region profile RMSE ({PROFILE_UNIT})')
    ax.set_title(f'overall ranking (mean over variants), reference '
                 f'{rk.get("reference", "?")}')
    ax.margins(x=0.15)
    ax = axs[0][1]
    h = 0.8 / max(n, 1)
    for j, m in enumerate(methods):
        ys, xs = [], []
        for i, s in enumerate(scenes):
            for e in s.get('methods', []):
                if str(e.get('method')) == m and math.isfinite(
                        num(e.get('mean'))):
                    ys.append(i + (j - (n - 1) / 2) * h)
                    xs.append(num(e.get('mean')))
        ax.barh(ys, xs, height=h, color=colors[m], label=m)
    ax.set_yticks(range(len(scenes)), [str(s.get('scene')) for s in scenes])
    ax.invert_yaxis()
    ax.set_xlabel(f'terminator-region profile RMSE ({PROFILE_UNIT})')
    ax.set_title('per scene')
    if methods:
        ax.legend(title='method', loc='lower right')
    return save(fig, figdir, 'ranking', written)


def fig_profiles(var, colors, figdir, written):
    renders = [r for r in var.get('renders') or [] if isinstance(r, dict)]
    gt = next((profile_xy(r.get('profile')) for r in renders
               if r.get('renderer') == REF and
               r.get('representation') == 'displacement'), None)
    others = sorted({str(r.get('renderer')) for r in renders} - {REF})
    dashes = [(0, (5, 2)), (0, (2, 1.5)), (0, (6, 2, 1, 2)), (0, (1, 1))]
    fig, (ax, ad) = plt.subplots(2, 1, figsize=(9.5, 7), sharex=True,
                                 height_ratios=[3, 2], layout='constrained')
    used = []
    for r in renders:
        xy = profile_xy(r.get('profile'))
        if xy is None:
            continue
        rend, rep = str(r.get('renderer')), str(r.get('representation'))
        meth = str(r.get('method'))
        is_gt = rep == 'displacement'
        lab = 'displacement (ground truth)' if is_gt else (
            meth if rep == 'bump' else f'{meth} ({rep})')
        if rend == REF:
            style = dict(color='k', lw=2.8, zorder=5) if is_gt else dict(
                color=colors.get(meth, 'C0'), lw=1.4)
        else:
            style = dict(color='0.35' if is_gt else colors.get(meth, 'C0'),
                         lw=1.2, ls=dashes[others.index(rend) % 4])
            lab = f'{rend}: {lab}'
        ax.plot(*xy, label=lab, **style)
        used.append(xy)
        if gt is not None and not (is_gt and rend == REF):
            ok = np.isfinite(gt[1])
            ref = np.interp(xy[0], gt[0][ok], gt[1][ok], left=math.nan,
                            right=math.nan) if ok.any() else xy[1] * math.nan
            ad.plot(xy[0], xy[1] - ref, label=lab, **style)
    for a in (ax, ad):
        a.axvspan(60, 100, color='0.9', zorder=0,
                  label='terminator region 60–100°' if a is ax else None)
        a.grid(alpha=0.3)
    ad.axhline(0, color='k', lw=0.8)
    finite = [x[np.isfinite(v)] for x, v in used if np.isfinite(v).any()]
    if finite:
        b = used[0][0][0]
        ad.set_xlim(max(0, min(f.min() for f in finite) - b),
                    min(180, max(f.max() for f in finite) + b))
    ax.set_ylabel(L_LABEL)
    ad.set_ylabel(f'Δ{L_LABEL}: method − truth')
    ad.set_xlabel(THETA_LABEL)
    ax.set_title(f'terminator profiles: {var.get("label", var.get("id"))}',
                 wrap=True)
    ad.set_title(f'difference from the {REF} displacement ground truth'
                 if gt is not None else 'no evaluator ground truth')
    ax.legend(loc='upper left', bbox_to_anchor=(1.01, 1.0))
    return save(fig, figdir, f'profiles-{stem(var.get("id"))}', written)


def axis_text(v, i):
    if isinstance(v, list):
        return f'#{i}: (' + ', '.join(fmt(t) for t in v) + ')'
    return fmt(v, digits=4) if isinstance(num(v), float) and \
        math.isfinite(num(v)) else str(v)


def axis_index(values, v):
    def same(a, b):
        if isinstance(a, list) and isinstance(b, list):
            return len(a) == len(b) and all(map(same, a, b))
        fa, fb = num(a), num(b)
        if math.isfinite(fa) and math.isfinite(fb):
            return math.isclose(fa, fb, rel_tol=1e-9, abs_tol=1e-12)
        return a == b
    return next((i for i, a in enumerate(values) if same(a, v)), None)


def contour_lines(ax, X, Y, z, levels, label_fmt):
    """Labelled black contour lines at the levels inside z's range."""
    inner = [v for v in levels if z.count() and z.min() < v < z.max()]
    if inner:
        cs = ax.contour(X, Y, z, levels=inner, colors='k', linewidths=0.6)
        ax.clabel(cs, fontsize=7, fmt=label_fmt)


def geometric(v):
    """Whether positive values are more evenly spaced on a log scale."""
    v = np.sort(np.asarray(v, dtype=float))
    if v.size < 3 or v[0] <= 0:
        return False
    def cv(d):
        return np.std(d) / np.mean(d) if np.mean(d) > 0 else math.inf
    return cv(np.diff(np.log(v))) < cv(np.diff(v))


def draw_grid(ax, grid, xs, ys, xlab, ylab, kind, norm, title):
    """One panel: contour when kind == 'contour', else annotated heatmap."""
    cmap = plt.get_cmap('viridis')
    if kind == 'contour':
        X, Y = np.meshgrid([num(v) for v in xs], [num(v) for v in ys])
        z = np.ma.masked_invalid(grid)
        levels = MaxNLocator(10).tick_values(norm.vmin, norm.vmax)
        im = ax.contourf(X, Y, z, levels=levels, cmap=cmap, norm=norm)
        contour_lines(ax, X, Y, z, levels, '%.3g')
        ax.plot(X.ravel(), Y.ravel(), 'o', color='w', ms=3.5, mec='k',
                mew=0.6, label='study samples')
        for v, set_scale in ((xs, ax.set_xscale), (ys, ax.set_yscale)):
            if geometric([num(t) for t in v]):
                set_scale('log')
        ax.minorticks_off()
        ax.set_xticks([num(v) for v in xs], [axis_text(v, i)
                                               for i, v in enumerate(xs)],
                      rotation=45, ha='right')
        ax.set_yticks([num(v) for v in ys], [axis_text(v, i)
                                               for i, v in enumerate(ys)])
        ax.legend(loc='upper right', fontsize=7)
    else:
        im = ax.imshow(grid, origin='lower', cmap=cmap, norm=norm,
                       aspect='auto')
        for (i, j), v in np.ndenumerate(grid):
            lum = np.dot(cmap(norm(v))[:3], [0.299, 0.587, 0.114])
            ax.text(j, i, fmt(v), ha='center', va='center', fontsize=8,
                    color='k' if (lum > 0.5 or not math.isfinite(v)) else 'w')
        ax.set_xticks(range(len(xs)), [axis_text(v, i)
                                       for i, v in enumerate(xs)],
                      rotation=30, ha='right')
        ax.set_yticks(range(len(ys)), [axis_text(v, i)
                                       for i, v in enumerate(ys)])
    ax.set_xlabel(xlab)
    ax.set_ylabel(ylab)
    ax.set_title(title)
    return im


def fig_plots(k, plot, doc, src, figdir, written):
    """Small multiples (one panel per method) for each scene of a plot."""
    axes = doc.get('axes') or []
    x, y = plot.get('x'), plot.get('y')
    if not all(isinstance(i, int) and 0 <= i < len(axes) for i in (x, y)) \
            or x == y:
        raise BadInput(src, f'plots[{k}]: x and y must be two different '
                       f'indices into axes (0..{len(axes) - 1}), got {x!r}, '
                       f'{y!r}')
    metric, rend = str(plot.get('metric')), str(plot.get('renderer', REF))
    xs, ys = axes[x].get('values') or [], axes[y].get('values') or []
    variants = {v.get('id'): v for v in doc.get('variants') or []
                if isinstance(v, dict)}
    cells = {}  # (scene, method) -> [sum grid, count grid]
    for c in doc.get('comparisons') or []:
        if not isinstance(c, dict) or c.get('renderer') != rend or \
                c.get('reference') != f'{rend}:displacement':
            continue
        var, val = variants.get(c.get('variant')), get_metric(c, metric)
        av = var.get('axis_values') if var else None
        if not isinstance(av, list) or len(av) != len(axes) or \
                not math.isfinite(val):
            continue
        i, j = axis_index(ys, av[y]), axis_index(xs, av[x])
        if i is None or j is None:
            continue
        key = (str(c.get('scene', var.get('scene'))), str(c.get('method')))
        acc = cells.setdefault(key, [np.zeros((len(ys), len(xs))),
                                     np.zeros((len(ys), len(xs)))])
        acc[0][i, j] += val
        acc[1][i, j] += 1
    numeric = all(len(v) >= 2 and all(math.isfinite(num(t)) for t in v)
                  for v in (xs, ys))
    ox = np.argsort([num(v) for v in xs]) if numeric else np.arange(len(xs))
    oy = np.argsort([num(v) for v in ys]) if numeric else np.arange(len(ys))
    xs, ys = [xs[i] for i in ox], [ys[i] for i in oy]
    out = []
    for scene in dict.fromkeys(s for s, _ in cells):
        grids = {}
        for (s, m), (tot, cnt) in cells.items():
            if s == scene:
                with np.errstate(invalid='ignore', divide='ignore'):
                    grids[m] = (tot / cnt)[np.ix_(oy, ox)]
        allv = np.concatenate([g[np.isfinite(g)] for g in grids.values()])
        lo, hi = (allv.min(), allv.max()) if allv.size else (0, 1)
        norm = plt.Normalize(lo, hi if hi > lo else lo + 1e-9)
        kind = 'contour' if plot.get('kind', 'contour') == 'contour' and \
            numeric and all(np.isfinite(g).sum() >= 4 for g in grids.values()) \
            else 'heatmap'
        labels = (str(axes[x].get('label', axes[x].get('pointer'))),
                  str(axes[y].get('label', axes[y].get('pointer'))))
        note = f'{rend} vs {rend}:displacement, {scene}'
        n = len(grids)
        fig, axs = plt.subplots(1, n, figsize=(4.2 * n + 1, 4.2),
                                layout='constrained', squeeze=False)
        for a, (m, g) in zip(axs[0], grids.items()):
            im = draw_grid(a, g, xs, ys, *labels, kind, norm, m)
            f1, a1 = plt.subplots(figsize=(5.4, 4.4), layout='constrained')
            im1 = draw_grid(a1, g, xs, ys, *labels, kind, norm, f'{m}: {note}')
            f1.colorbar(im1, ax=a1, label=metric_label(metric))
            save(f1, figdir, f'plot-{k}-{stem(scene)}-{stem(metric)}-'
                 f'{stem(m)}', written)
        fig.colorbar(im, ax=axs[0].tolist(), label=metric_label(metric))
        fig.suptitle(f'{metric_label(metric)}: {note} (mean over other axes)')
        out.append((scene, save(fig, figdir, f'plot-{k}-{stem(scene)}',
                                written)))
    return metric, rend, out


CSS = """body{font:15px/1.45 system-ui,sans-serif;max-width:1400px;
margin:1em auto;padding:0 1em;color:#222}h1,h2,h3{font-weight:600}
h2{border-bottom:2px solid #ddd;margin-top:2em}table{border-collapse:collapse;
margin:.5em 0 1em}td,th{border:1px solid #ccc;padding:3px 7px;
vertical-align:top}th{background:#f3f3f3}td.n{text-align:right;
font-variant-numeric:tabular-nums}.na{color:#999}img{max-width:100%}
.fail td{color:#b00}.grid img{width:190px;image-rendering:pixelated}
figure{margin:0}figcaption{font-size:12px;color:#555}footer{margin-top:3em;
border-top:1px solid #ddd;font-size:13px;color:#555}nav a{margin-right:1em}"""


def table(head, rows, cls=''):
    """An HTML table; cells are (text, numeric) pairs, text already escaped."""
    h = ''.join(f'<th>{esc(c)}</th>' for c in head)

    def td(t, n):
        c = ' '.join(['n'] * n + ['na'] * (t == 'n/a'))
        return f'<td class="{c}">{t}</td>' if c else f'<td>{t}</td>'
    body = ''.join(f'\n<tr{cls}>' + ''.join(td(t, n) for t, n in r) +
                   '</tr>' for r in rows)
    return f'<table><tr>{h}</tr>{body}</table>'


def img(uri, alt, cap=''):
    c = f'<figcaption>{esc(cap)}</figcaption>' if cap else ''
    return f'<figure><img src="{uri}" alt="{esc(alt)}">{c}</figure>'


def variant_html(var, out, comps, missing, fig, renderers):
    vid, renders = str(var.get('id')), var.get('renders') or []
    where = (os.path.join(out, 'report.json'), f'variant {vid}')

    def col(r):
        rep = str(r.get('representation'))
        return 'ground truth (displacement)' if rep == 'displacement' else (
            str(r.get('method')) if rep == 'bump' else
            f'{r.get("method")} ({rep})')
    renders = [r for r in renders if isinstance(r, dict)]
    cols = list(dict.fromkeys(['ground truth (displacement)'] +
                              [col(r) for r in renders]))
    rows = list(dict.fromkeys(renderers + [str(r.get('renderer'))
                                           for r in renders]))
    at = {(str(r.get('renderer')), col(r)): r for r in renders}
    grid = '<tr><th>renderer</th>' + ''.join(f'<th>{esc(c)}</th>'
                                             for c in cols) + '</tr>'
    for rend in rows:
        if not any((rend, c) in at for c in cols):
            continue
        line, diff = f'<tr><th>{esc(rend)}</th>', '<tr><th>difference</th>'
        for c in cols:
            r = at.get((rend, c))
            if r is None:
                why = missing.get((rend, c), 'not rendered')
                line += f'<td class="na">{esc(why)}</td>'
                diff += '<td></td>'
                continue
            if isinstance(r.get('image'), str):
                line += '<td>' + img(data_uri(inside(
                    out, r['image'], where), where), f'{rend} {c}',
                    f'{rend} / {c}') + '</td>'
            else:
                line += '<td class="na">no image</td>'
            d = r.get('difference')
            diff += '<td>' + (img(data_uri(inside(out, d, where), where),
                                  f'{rend} {c} difference',
                                  f'{c} − displacement ({rend})')
                              if isinstance(d, str) else '') + '</td>'
        grid += line + '</tr>'
        if any(isinstance(at.get((rend, c), {}).get('difference'), str)
               for c in cols):
            grid += diff + '</tr>'
    pct = [('profile.rmse_terminator', 100), ('profile.rmse_overall', 100),
           ('profile.max_error_terminator', 100), ('profile.max_step', 100),
           ('profile.position_error_deg', 1), ('profile.width_deg', 1),
           ('profile.lit_bias', 100), ('image.rmse', 1), ('image.ssim', 1)]
    rows = [[(esc(c.get('renderer')), False), (esc(c.get('method')), False),
             (esc(c.get('reference')), False)] +
            [(fmt(get_metric(c, m), s), True) for m, s in pct] for c in comps]
    head = ['renderer', 'method', 'reference', 'terminator RMSE (%)',
            'overall RMSE (%)', 'max error (%)', 'max step (%)',
            'position error (deg)', 'width (deg)', 'lit bias (%)',
            'image RMSE (W m⁻² sr⁻¹)', 'SSIM']
    return (f'<h2 id="v-{esc(stem(vid))}">{esc(vid)}: '
            f'{esc(var.get("label", ""))}</h2><h3>Images</h3>'
            f'<table class="grid">{grid}</table><h3>Terminator profiles</h3>'
            + img(data_uri(fig, where), f'profiles {vid}') +
            '<h3>Metrics</h3>' + (table(head, rows) if rows else
                                  '<p class="na">no comparisons</p>'))


def run_report(out):
    doc = load_json(os.path.join(out, 'report.json'), 'penumbra-report')
    where = os.path.join(out, 'report.json')
    for key in ('axes', 'renderers', 'variants', 'comparisons', 'missing',
                'failures', 'plots'):
        if not isinstance(doc.get(key, []), list):
            raise BadInput(where, f'"{key}" must be an array')
    for i, a in enumerate(doc.get('axes', [])):
        if not isinstance(a, dict) or not isinstance(a.get('values'), list):
            raise BadInput(where, f'axes[{i}]: expected an object with '
                           '"values": [...]')
    if not isinstance(doc.get('ranking', {}), dict):
        raise BadInput(where, '"ranking" must be an object')
    figdir, written = os.path.join(out, 'figures'), []
    os.makedirs(figdir, exist_ok=True)
    rends = [r for r in doc.get('renderers', []) if isinstance(r, dict)]
    rk = doc.get('ranking') or {}
    variants = [v for v in doc.get('variants', []) if isinstance(v, dict)]
    comps = [c for c in doc.get('comparisons', []) if isinstance(c, dict)]
    colors = method_colors(
        [str(m) for r in rends for m in r.get('methods') or []] +
        [str(e.get('method')) for e in rk.get('overall') or []
         if isinstance(e, dict)] +
        [str(r.get('method')) for v in variants for r in v.get('renders')
         or [] if isinstance(r, dict)] + [str(c.get('method')) for c in comps])
    study = doc.get('study') if isinstance(doc.get('study'), dict) else {}
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
             '<a href="#plots">Sweeps</a></nav>',
             '<h2 id="headline">Headline</h2>']
    parts.append(f'<p>Metric {esc(rk.get("metric", "?"))} of renderer '
                 f'{esc(rk.get("renderer", "?"))} against '
                 f'{esc(rk.get("reference", "?"))}; lower is better.</p>')
    groups = [('overall', rk.get('overall') or [])] + [
        (f'scene {s.get("scene")}', s.get('methods') or [])
        for s in rk.get('per_scene') or [] if isinstance(s, dict)]
    for name, entries in groups:
        rows = [[(esc(e.get('method')), False),
                 (fmt(e.get('mean'), 100, 3), True),
                 (str(i + 1), True), (esc(e.get('count', '')), True)]
                for i, e in enumerate(x for x in entries if isinstance(x, dict))]
        parts.append(f'<h3>{esc(name)}</h3>' + table(
            ['method', 'mean terminator-region RMSE (%)', 'rank', 'count'],
            rows))
    fig = fig_ranking(rk, colors, figdir, written)
    if fig:
        parts.append(img(data_uri(fig, (fig, 'figure')), 'ranking',
                         'figures/ranking.{png,svg,pdf}'))
    rows = [[(esc(r.get('id')), False), (esc(r.get('version', '')), False),
             (esc(', '.join(map(str, r.get('methods') or []))), False),
             (esc(r.get('note', '')), False)] for r in rends]
    parts.append('<h2 id="renderers">Renderers</h2>' + table(
        ['renderer', 'version', 'methods', 'note'], rows))
    miss = [m for m in doc.get('missing', []) if isinstance(m, dict)]
    if miss:
        parts.append('<h3>Rows a renderer cannot provide</h3>' + table(
            ['renderer', 'method', 'why'],
            [[(esc(m.get(k, '')), False) for k in ('renderer', 'method',
                                                   'why')] for m in miss]))
    fails = [f for f in doc.get('failures', []) if isinstance(f, dict)]
    if fails:
        parts.append('<h3 style="color:#b00">Failures</h3>' + table(
            ['render', 'error'], [[(esc(f.get('render', '')), False),
                                   (esc(f.get('error', '')), False)]
                                  for f in fails], ' class="fail"'))
    missing = {(str(m.get('renderer')), str(m.get('method'))):
               str(m.get('why', '')) for m in miss}
    for v in variants:
        fig = fig_profiles(v, colors, figdir, written)
        parts.append(variant_html(
            v, out, [c for c in comps if c.get('variant') == v.get('id')],
            missing, fig, [str(r.get('id')) for r in rends]))
    parts.append('<h2 id="plots">Sweeps</h2>')
    for k, plot in enumerate(doc.get('plots', [])):
        if not isinstance(plot, dict):
            raise BadInput(where, f'plots[{k}] must be an object')
        metric, rend, figs = fig_plots(k, plot, doc, where, figdir, written)
        parts.append(f'<h3>{esc(metric_label(metric))}, {esc(rend)}</h3>')
        parts += [img(data_uri(f, (f, 'figure')), f'plot {k} {s}',
                      f'scene {s}: figures/{os.path.basename(f)[:-4]}'
                      '.{png,svg,pdf}') for s, f in figs] or [
            '<p class="na">no finite values for this plot</p>']
    parts.append(
        '<footer><p>Profile values are fractions of albedo·E/π (a smooth '
        'Lambertian surface gives cos θ). θ is the angle between the light '
        'direction and the base-surface normal, in degrees; the terminator '
        'region is 60–100°, the lit region θ &lt; 60°. RMSE and bias in the '
        'tables are in percent of albedo·E/π; image metrics are in the '
        'image unit (' + esc((doc.get('units') or {}).get(
            'image', 'W m^-2 sr^-1')) + '). Figures are in '
        'figures/ as PNG, SVG and PDF.</p></footer></body></html>\n')
    path = os.path.join(out, 'report.html')
    with open(path, 'w', encoding='utf-8') as f:
        f.write('\n'.join(parts))
    return written + [path]


# --------------------------------------------------------------- contour ---

def contour_panel(ax, L, D, G, title, diff=None):
    """G (or a difference when diff is its symmetric limit) over (L, D)."""
    if diff is None:
        levels, cmap, lines = np.linspace(0, 1, 11), 'viridis', None
    else:
        levels, cmap = np.linspace(-diff, diff, 21), 'RdBu'
        lines = MaxNLocator(8, symmetric=True).tick_values(-diff, diff)
    z = np.ma.masked_invalid(G)
    extend = 'neither' if diff is not None or not z.count() or (
        z.min() >= 0 and z.max() <= 1) else 'both'
    if z.count():
        im = ax.contourf(L, D, z, levels=levels, cmap=cmap, extend=extend)
        contour_lines(ax, L, D, z, levels if lines is None else lines,
                      '%.2g')
    else:
        ax.text(0.5, 0.5, 'undefined everywhere', transform=ax.transAxes,
                ha='center')
        ax.set_xlim(L[0], L[-1])
        ax.set_ylim(D[0], D[-1])
        im = plt.cm.ScalarMappable(plt.Normalize(levels[0], levels[-1]),
                                   cmap)
    lo, hi = max(L[0], D[0]), min(L[-1], D[-1])
    ax.plot([lo, hi], [lo, hi], '--', color='w', lw=1.3,
            label='y = x: shading normal points at the light',
            path_effects=[patheffects.withStroke(linewidth=2.6,
                                                 foreground='k')])
    ax.legend(loc='upper left', fontsize=7)
    ax.set_xlabel('light angle from Ng (degrees)')
    ax.set_ylabel('shading-normal deviation towards the light (degrees)')
    ax.set_title(title)
    return im


def run_contour(path, outdir):
    doc = load_json(path, 'penumbra-contour')
    L, D = farray(doc.get('light_deg')), farray(doc.get('deviation_deg'))
    for name, a in (('light_deg', L), ('deviation_deg', D)):
        if a.size < 2 or not np.all(np.isfinite(a)) or np.any(np.diff(a) <= 0):
            raise BadInput(path, f'"{name}" must be >= 2 increasing numbers')
    methods = doc.get('methods')
    if not isinstance(methods, list) or not methods:
        raise BadInput(path, '"methods" must be a non-empty array')
    G = {}
    for i, m in enumerate(methods):
        g = m.get('G') if isinstance(m, dict) else None
        if not isinstance(m, dict) or not isinstance(m.get('id'), str) or \
                not isinstance(g, list) or len(g) != D.size or \
                any(not isinstance(r, list) or len(r) != L.size for r in g):
            raise BadInput(path, f'methods[{i}]: expected {{"id": string, '
                           f'"G": {D.size} rows of {L.size} numbers}}')
        G[m['id']] = np.array([farray(r) for r in g])
    os.makedirs(outdir, exist_ok=True)
    written = []

    def diff_limit(d):
        m = np.nanmax(np.abs(d)) if np.isfinite(d).any() else 0
        return float(m) if m > 0 else 1e-3

    def diff_title(a, b):
        return f'G[{a}] − G[{b}]\npositive: {a} lets more light through'
    for m, g in G.items():
        fig, ax = plt.subplots(figsize=(5.6, 4.6), layout='constrained')
        im = contour_panel(ax, L, D, g, f'terminator factor G: {m}')
        fig.colorbar(im, ax=ax, label='G (fraction of light let through)')
        save(fig, outdir, f'contour-{stem(m)}', written)
    ids = list(G)
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            d = G[a] - G[b]
            fig, ax = plt.subplots(figsize=(5.6, 4.8), layout='constrained')
            im = contour_panel(ax, L, D, d, diff_title(a, b), diff_limit(d))
            fig.colorbar(im, ax=ax, label=f'G[{a}] − G[{b}]')
            save(fig, outdir, f'contour-diff-{stem(a)}-{stem(b)}', written)
    n = len(ids) + (len(ids) >= 2)
    fig, axs = plt.subplots(1, n, figsize=(4.3 * n + 1, 4.6),
                            layout='constrained', squeeze=False)
    for ax, m in zip(axs[0], ids):
        im = contour_panel(ax, L, D, G[m], m)
    fig.colorbar(im, ax=axs[0][:len(ids)].tolist(), label='G')
    if len(ids) >= 2:
        d = G[ids[0]] - G[ids[1]]
        im = contour_panel(axs[0][-1], L, D, d, diff_title(*ids[:2]),
                           diff_limit(d))
        fig.colorbar(im, ax=axs[0][-1], label='difference of G')
    save(fig, outdir, 'contour', written)
    return written


def main(argv):
    usage = ('usage: report.py report OUT | '
             'report.py contour CONTOUR.json OUTDIR')
    try:
        if len(argv) == 2 and argv[0] == 'report':
            written = run_report(argv[1])
        elif len(argv) == 3 and argv[0] == 'contour':
            written = run_contour(argv[1], argv[2])
        else:
            print(usage, file=sys.stderr)
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
