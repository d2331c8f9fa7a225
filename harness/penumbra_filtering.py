"""The figures of `penumbra filtering` (report.py filtering).

Reads filtering.json ("format": "penumbra-filtering", "version": 1:
options{alphas[]}, cells[{filter, alpha, level, texels_per_pixel,
energy_ratio, width_ratio, profile_error}], each metric {mean,
interval[low, high], n}; null where undefined) and writes into OUTDIR
filtering-<metric>.* (or PREFIX-<metric>.* in a study report) for profile_error, width_ratio and energy_ratio: one
panel per base roughness, the metric against texels per pixel, one line
per filter with its 95 % interval as error bars. PNG, SVG and PDF.
"""
import numpy as np

from penumbra_data import BadInput, farray, load_json, num, obj, objs
from penumbra_plot import plt, save
from penumbra_style import method_colors

METRICS = (('profile_error', 'profile error (L2 / reference)', 0.0),
           ('width_ratio', 'highlight width / reference', 1.0),
           ('energy_ratio', 'highlight energy / reference', 1.0))


def load_filtering(path):
    """(alphas, filters in order, {(filter, alpha): rows sorted by level})."""
    doc = load_json(path, 'penumbra-filtering')
    alphas = farray(obj(doc.get('options')).get('alphas'))
    cells = objs(doc.get('cells'))
    if alphas.size == 0 or not cells:
        raise BadInput(path, 'expected options.alphas and cells')
    filters, series = [], {}
    for i, c in enumerate(cells):
        f, a, t = c.get('filter'), num(c.get('alpha')), num(c.get('texels_per_pixel'))
        if not isinstance(f, str) or not np.isfinite(a) or not t > 0:
            raise BadInput(path, f'cells[{i}]: expected filter, alpha and '
                           'texels_per_pixel')
        if f not in filters:
            filters.append(f)
        series.setdefault((f, a), []).append(c)
    for rows in series.values():
        rows.sort(key=lambda c: num(c.get('texels_per_pixel')))
    return alphas, filters, series


def metric_figure(alphas, filters, series, metric, label, ideal, outdir,
                  prefix='filtering'):
    colors = method_colors(filters)
    cols = min(3, alphas.size)
    rows_n = (alphas.size + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, 3.2 * rows_n),
                             squeeze=False, sharex=True)
    for k, alpha in enumerate(alphas):
        ax = axes[k // cols][k % cols]
        for f in filters:
            rows = series.get((f, alpha), [])
            t = farray([c.get('texels_per_pixel') for c in rows])
            m = [obj(c.get(metric)) for c in rows]
            mean = farray([x.get('mean') for x in m])
            iv = [x.get('interval') if isinstance(x.get('interval'), list) else [None, None]
                  for x in m]
            low = mean - farray([v[0] for v in iv])
            high = farray([v[1] for v in iv]) - mean
            # Clipped at 0: where every footprint gives the same value the
            # summed mean can lie an ulp outside its [x, x] interval.
            err = np.clip(np.nan_to_num(np.vstack([low, high]), nan=0.0),
                          0.0, None)
            ax.errorbar(t, mean, yerr=err, label=f, color=colors[f], marker='o',
                        markersize=3, linewidth=1, capsize=2)
        ax.axhline(ideal, color='k', linewidth=0.5)
        ax.set_xscale('log', base=2)
        ax.set_title(f'base GGX alpha = {alpha:g}')
        ax.set_xlabel('texels per pixel (side)')
        ax.set_ylabel(label)
    for k in range(alphas.size, rows_n * cols):
        axes[k // cols][k % cols].axis('off')
    axes[0][0].legend(loc='best')
    fig.suptitle(f'{label}: mean over footprints, 95 % bootstrap interval')
    return save(fig, outdir, f'{prefix}-{metric}')


def filtering_figures(path, outdir, prefix='filtering'):
    """Writes OUTDIR/PREFIX-<metric>.{png,svg,pdf}; returns the paths, PNG
    first for each metric."""
    alphas, filters, series = load_filtering(path)
    written = []
    for metric, label, ideal in METRICS:
        written += metric_figure(alphas, filters, series, metric, label, ideal,
                                 outdir, prefix)
    return written
