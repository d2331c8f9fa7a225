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


# Inches: a cell, the margins for the row and column heads, the gap
# between cells (a fraction of a cell).
CELL_W, CELL_H, HEAD_W, HEAD_H, GAP = 1.7, 1.75, 0.9, 0.9, 0.02


def _extent(shape, i, j, cw, ch):
    """Where an image of `shape` (rows, columns) goes in cell (i, j) of the
    grid axes (one unit per cell, rows downwards): as large as the cell
    allows at the image's own aspect ratio, centred."""
    rows, cols = shape[0], shape[1]
    w, h = 1.0 - 2 * GAP, 1.0 - 2 * GAP
    if cols * ch * h > rows * cw * w:  # wider than the cell
        h = w * cw * rows / (cols * ch)
    else:
        w = h * ch * cols / (rows * cw)
    x0, y0 = j + 0.5 - w / 2, i + 0.5 - h / 2
    return (x0, x0 + w, y0 + h, y0)


def grid_figure(var, out, src, renderers, figdir):
    """figures/grid-<variant>.{png,pdf}; returns the paths written ([]
    when the variant has no images)."""
    cols, rows = _cells(var, renderers)
    if not rows:
        return []
    # One axes in cell units for the whole grid: an axes per cell costs
    # seconds per variant (each builds its own ticks), and a study draws
    # one grid per variant. save() trims the figure to what was drawn.
    nr, nc = len(rows), len(cols)
    fig = plt.figure(figsize=(CELL_W * nc + HEAD_W, CELL_H * nr + HEAD_H))
    ax = fig.add_axes((HEAD_W / fig.get_figwidth(), 0.0,
                       CELL_W * nc / fig.get_figwidth(),
                       CELL_H * nr / fig.get_figheight()))
    ax.set_axis_off()
    for j, name in enumerate(cols):
        ax.text(j + 0.5, -GAP, name.replace(' (', '\n('), ha='center',
                va='bottom', fontsize=8)
    for i, (head, paths) in enumerate(rows):
        ax.text(-GAP, i + 0.5, head, ha='right', va='center', fontsize=8,
                rotation=90, multialignment='center')
        for j, rel in enumerate(paths):
            if rel is not None:
                ctx = f'variant {var.get("id")}: image'
                img = mpimg.imread(inside(out, rel, src, ctx))
                ax.imshow(img, interpolation='nearest', aspect='auto',
                          extent=_extent(img.shape, i, j, CELL_W, CELL_H))
            elif not head.endswith('difference'):
                ax.text(j + 0.5, i + 0.5, 'not\nprovided', ha='center',
                        va='center', fontsize=7, color='0.5')
    ax.set_xlim(0, nc)  # after imshow, which sets them to each image's extent
    ax.set_ylim(nr, 0)
    fig.suptitle(str(var.get('label', var.get('id'))), fontsize=9,
                 wrap=True, va='bottom',
                 y=(CELL_H * nr + 0.5) / fig.get_figheight())
    return save(fig, figdir, f'grid-{stem(var.get("id"))}', ('png', 'pdf'))
