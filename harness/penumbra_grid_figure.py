"""The composed image grid of a variant (Chiang et al. 2019, Fig. 4 style):
one figure a reader can put in a paper, figures/grid-<variant>.{png,pdf}.

Columns: the displacement ground truth, then every method; rows: each
renderer's renders, each followed by its difference images (method minus
the same renderer's ground truth, as the page shows them). A cell a
renderer cannot provide is left blank with a short reason. The images are
the study's own PNGs (images/), drawn at their pixel size without
resampling artefacts (nearest neighbour).
"""
import matplotlib.image as mpimg

from penumbra_data import GROUND_TRUTH, column, inside, objs, stem
from penumbra_plot import plt, save


def _cells(var, renderers):
    """(columns, rows): rows of (head, [image path relative to OUT or None,
    per column])."""
    renders = objs(var.get('renders'))
    cols = list(dict.fromkeys([GROUND_TRUTH] + [column(r) for r in renders]))
    at = {(str(r.get('renderer')), column(r)): r for r in renders}
    rows = []
    for rend in dict.fromkeys(renderers + [k[0] for k in at]):
        rs = [at.get((rend, c)) for c in cols]
        if not any(rs):
            continue
        rows.append((rend, [r.get('image') if r else None for r in rs]))
        diffs = [r.get('difference') if r else None for r in rs]
        if any(d is not None for d in diffs):
            rows.append((f'{rend}\ndifference', diffs))
    return cols, rows


def grid_figure(var, out, src, renderers, figdir):
    """figures/grid-<variant>.{png,pdf}; returns the paths written ([]
    when the variant has no images)."""
    cols, rows = _cells(var, renderers)
    if not rows:
        return []
    # Fixed margins rather than a constrained layout, which costs seconds
    # over this many axes; save() trims the figure to what was drawn.
    fig, axs = plt.subplots(len(rows), len(cols), squeeze=False,
                            figsize=(1.7 * len(cols) + 0.9,
                                     1.75 * len(rows) + 0.9),
                            gridspec_kw=dict(wspace=0.04, hspace=0.04,
                                             left=0.07, right=0.99,
                                             bottom=0.01, top=0.92))
    for i, (head, paths) in enumerate(rows):
        for j, rel in enumerate(paths):
            ax = axs[i][j]
            ax.set_xticks([])
            ax.set_yticks([])
            for side in ax.spines.values():
                side.set_visible(False)
            if rel is not None:
                ctx = f'variant {var.get("id")}: image'
                ax.imshow(mpimg.imread(inside(out, rel, src, ctx)),
                          interpolation='nearest')
            elif not head.endswith('difference'):
                ax.text(0.5, 0.5, 'not\nprovided', ha='center',
                        va='center', fontsize=7, color='0.5',
                        transform=ax.transAxes)
            if j == 0:
                ax.set_ylabel(head, fontsize=8)
            if i == 0:
                ax.set_title(cols[j].replace(' (', '\n('), fontsize=8)
    fig.suptitle(str(var.get('label', var.get('id'))), fontsize=9,
                 wrap=True)
    return save(fig, figdir, f'grid-{stem(var.get("id"))}', ('png', 'pdf'))
