"""The contour plots of `penumbra contour` (report.py contour).

Reads the contour JSON ("format": "penumbra-contour", "version": 1:
light_deg[], deviation_deg[], methods[{id, G[deviation][light]}], null
where G is undefined) and writes into OUTDIR contour-<method>.*,
contour-diff-<a>-<b>.* for every pair of methods in the given order, and
the combined contour.*, each as PNG, SVG and PDF.
"""
import os

import numpy as np
from matplotlib import patheffects
from matplotlib.ticker import MaxNLocator

from penumbra_data import BadInput, farray, load_json, obj, stem
from penumbra_plot import contour_lines, plt, save


def load_contour(path):
    """(light angles L, deviations D, {method: G[D][L]}), checked."""
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
    return L, D, G


def contour_panel(ax, L, D, G, title, diff=None, levels=None, lines=None):
    """G on levels (default 0 to 1 in tenths: a factor that only darkens),
    or a difference when diff is given (its symmetric limit); lines: the
    labelled contour lines (default: every level, or 8 for a difference),
    fewer where the values are noisy (a floor fitted cell by cell)."""
    if diff is None:
        cmap = 'viridis'
        levels = np.linspace(0, 1, 11) if levels is None else levels
    else:
        levels = MaxNLocator(20, symmetric=True).tick_values(-diff, diff)
        cmap = 'RdBu'
        if lines is None:
            lines = MaxNLocator(8, symmetric=True).tick_values(-diff, diff)
    z = np.ma.masked_invalid(G)
    if z.count():
        extend = 'both' if diff is None and (z.min() < levels[0] or
                                             z.max() > levels[-1]) \
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
    # A long handle: a short one shows only the stroke's caps.
    ax.legend(loc='upper left', fontsize=7, handlelength=4, borderpad=0.6)
    if diff is None and z.count():
        zoom_inset(ax, L, D, z, levels, cmap)
    ax.set(xlabel='light angle from Ng (degrees)', title=title,
           ylabel='shading-normal deviation towards the light (degrees)')
    return im


def transition(L, z, level=0.995):
    """The light angles where G departs from 1 somewhere: (first, last),
    or None when it never does."""
    cols = np.flatnonzero(np.ma.any(z < level, axis=0).filled(False))
    return (L[cols[0]], L[cols[-1]]) if cols.size else None


def zoom_inset(ax, L, D, z, levels, cmap):
    """When G falls from 1 to 0 within a quarter of the light angles (e.g.
    deshmukh2020, all near 90°), an inset that zooms on those angles, so
    its contours can be read."""
    t = transition(L, z)
    span = L[-1] - L[0]
    if t is None or t[1] - t[0] > 0.25 * span:
        return
    x0 = max(L[0], t[0] - 0.1 * max(t[1] - t[0], 1.0))
    x1 = min(L[-1], t[1] + 0.05 * max(t[1] - t[0], 1.0))
    ins = ax.inset_axes([0.38, 0.1, 0.4, 0.45])
    ins.contourf(L, D, z, levels=levels, cmap=cmap)
    contour_lines(ins, L, D, z, levels, '%.2g')
    ins.set_xlim(x0, x1)
    ins.set_ylim(D[0], D[-1])
    ins.tick_params(labelsize=7)
    ins.set_title(f'zoom: {x0:.3g}–{x1:.3g}°', fontsize=7)
    ax.indicate_inset_zoom(ins, edgecolor='w')


def diff_panel(ax, fig, L, D, G, a, b):
    """G[a] - G[b] with its colour bar, symmetric around 0."""
    d = G[a] - G[b]
    lim = np.nanmax(np.abs(d)) if np.isfinite(d).any() else 0
    im = contour_panel(ax, L, D, d, f'G[{a}] − G[{b}]\npositive: {a} '
                       'lets more light through', float(lim) or 1e-3)
    fig.colorbar(im, ax=ax, label=f'G[{a}] − G[{b}]')


def contour_figures(L, D, G, outdir):
    """Every contour figure; returns the paths written."""
    os.makedirs(outdir, exist_ok=True)
    written, ids = [], list(G)
    for m, g in G.items():
        fig, ax = plt.subplots(figsize=(5.6, 4.6), layout='constrained')
        im = contour_panel(ax, L, D, g, f'terminator factor G: {m}')
        fig.colorbar(im, ax=ax, label='G (fraction of light let through)')
        written += save(fig, outdir, f'contour-{stem(m)}')
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            fig, ax = plt.subplots(figsize=(5.6, 4.8), layout='constrained')
            diff_panel(ax, fig, L, D, G, a, b)
            written += save(fig, outdir, f'contour-diff-{stem(a)}-{stem(b)}')
    n = len(ids) + (len(ids) >= 2)
    fig, axs = plt.subplots(1, n, figsize=(4.3 * n + 1, 4.6),
                            layout='constrained', squeeze=False)
    for ax, m in zip(axs[0], ids):
        im = contour_panel(ax, L, D, G[m], m)
    fig.colorbar(im, ax=axs[0][:len(ids)].tolist(), label='G')
    if len(ids) >= 2:
        diff_panel(axs[0][-1], fig, L, D, G, ids[0], ids[1])
    return written + save(fig, outdir, 'contour')
