"""The composed image grid of a variant (Chiang et al. 2019, Fig. 4 style):
a figure a reader can put in a paper, figures/grid-<variant>.{png,pdf}: the
ground truth and the handful of methods the report highlights (penumbra_
stats.highlighted), every renderer that has one. Every method's grid, in
bands of at most BAND_COLUMNS columns (the ground truth first in each band,
each band with only the renderers that provide one of its methods: 21
columns of mostly "not provided" read as nothing), is the page's (bands()
serves both) and `report.py figure --kind grid --methods all`.

Columns: the displacement ground truth, then methods; rows: each renderer's
renders, each followed by its difference images (method minus the same
renderer's ground truth, as the page shows them), with a labelled
diverging colour bar (the map the C++ side draws them with,
study/previews.h), and its HDR-FLIP maps against that truth, with the
magma colour bar the FLIP papers use. A column no renderer provides is dropped. The images are
the study's own PNGs (images/), drawn at their pixel size without
resampling artefacts (nearest neighbour).
"""
import re

import matplotlib.image as mpimg
from matplotlib.colors import LinearSegmentedColormap, Normalize

# The two kinds of picture rows below a renderer's renders, by their heads.
PICTURE_ROWS = ('difference', 'FLIP')

from penumbra_data import FRACTION, GROUND_TRUTH, column, inside, objs, stem
from penumbra_plot import plt, save

BAND_COLUMNS = 7
# study/previews.cpp: blue (darker) - white (equal) - red (brighter),
# linear, saturating at +-0.25 albedo*E/pi.
DIFF_LIMIT = 0.25
DIFF_MAP = LinearSegmentedColormap.from_list(
    'penumbra-difference', [(0, 0, 1), (1, 1, 1), (1, 0, 0)])


def grid_renders(var, renderers, methods=None):
    """(columns, [(renderer, [its render or None per column])]): the
    ground truth, then the bump renders of `methods` (all when None) in
    that order, without columns no renderer provides; renderers in the
    given order, then any other, each only if it has a render. The page's
    grid (penumbra_html) and the figures share it."""
    renders = objs(var.get('renders'))
    keep = [r for r in renders if methods is None or
            r.get('representation') == 'displacement' or
            str(r.get('method')) in methods]
    order = {m: i for i, m in enumerate(methods or [])}
    cols = list(dict.fromkeys([GROUND_TRUTH] + sorted(
        (column(r) for r in keep if column(r) != GROUND_TRUTH),
        key=lambda c: order.get(c.split(' (')[0], 0))))
    at = {(str(r.get('renderer')), column(r)): r for r in keep}
    rows = []
    for rend in dict.fromkeys(renderers + [k[0] for k in at]):
        rs = [at.get((rend, c)) for c in cols]
        if any(rs):
            rows.append((rend, rs))
    return cols, rows


def _cells(var, renderers, methods=None):
    """(columns, rows): rows of (head, [image path relative to OUT or None,
    per column]), each renderer's images, then its differences, then its
    FLIP maps."""
    cols, renders = grid_renders(var, renderers, methods)
    rows = []
    for rend, rs in renders:
        rows.append((rend, [r.get('image') if r else None for r in rs]))
        diffs = [r.get('difference') if r else None for r in rs]
        if any(d is not None for d in diffs):
            rows.append((f'{rend}\ndifference', diffs))
        flips = [r.get('flip_map') if r else None for r in rs]
        if any(f is not None for f in flips):
            rows.append((f'{rend}\nFLIP', flips))
    return cols, rows


# Inches: a cell, the margins for the row and column heads, the gap
# between cells (a fraction of a cell).
CELL_W, CELL_H, HEAD_W, GAP = 1.7, 1.75, 0.9, 0.02


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


def bands(cols, rows, width=None):
    """The grid cut into bands of at most `width` (BAND_COLUMNS) columns,
    the ground truth first in each; in each band only the rows with
    something besides the ground truth. rows: (head, [cell or None per
    column]), image paths or renders."""
    width = width or BAND_COLUMNS
    if len(cols) <= width:
        return [(cols, rows)]
    out = []
    for k in range(1, len(cols), width - 1):
        idx = [0] + list(range(k, min(k + width - 1, len(cols))))
        band = [(head, [paths[j] for j in idx]) for head, paths in rows]
        keep = [r for r in band if any(p is not None for p in r[1][1:])]
        out.append(([cols[j] for j in idx], keep))
    return out


def _head(name, chars):
    """A column head in lines of about `chars` characters, broken at
    spaces, after a '-' or before a '(' (method ids have no spaces)."""
    marked = name.replace('-', '-\0').replace('(', '\0(')
    lines = ['']
    for token in re.findall(r'[^ \0]+[ \0]?', marked):
        if lines[-1] and len((lines[-1] + token).replace('\0', '').rstrip()) > chars:
            lines.append('')
        lines[-1] += token
    return '\n'.join(t.replace('\0', '').rstrip() for t in lines)


def _heads(cols, width):
    """(font size, heads in lines, slanted?) of the column heads of cells
    `width` inches wide: too narrow for a word of a head, every head is
    slanted, on one line."""
    size = 8 if width >= 1.4 else 7
    chars = int(width * 72 / (0.6 * size))
    heads = [_head(name, chars) for name in cols]
    slant = max(len(w) for h in heads for w in h.split('\n')) > chars
    return size, heads, slant


def _head_height(cols, width):
    """Inches above a band for its column heads."""
    size, heads, slant = _heads(cols, width)
    if not slant:
        return 0.15 + 0.17 * max(h.count('\n') + 1 for h in heads) * size / 8
    return 0.15 + 0.55 * size / 72 * max(map(len, cols)) * 0.58


def _draw_band(ax, var, out, src, cols, rows, cell):
    """One band of the grid on an axes in cell units (rows downwards);
    cell: a cell's (width, height) in inches."""
    ax.set_axis_off()
    size, heads, slant = _heads(cols, cell[0])
    for j, name in enumerate(cols):
        if slant:
            ax.text(j + 0.25, -GAP, name, ha='left', va='bottom',
                    fontsize=size, rotation=35, rotation_mode='anchor')
        else:
            ax.text(j + 0.5, -GAP, heads[j], ha='center', va='bottom',
                    fontsize=size)
    for i, (head, paths) in enumerate(rows):
        ax.text(-GAP, i + 0.5, head, ha='right', va='center', fontsize=size,
                rotation=90, multialignment='center')
        for j, rel in enumerate(paths):
            if rel is not None:
                ctx = f'variant {var.get("id")}: image'
                img = mpimg.imread(inside(out, rel, src, ctx))
                ax.imshow(img, interpolation='nearest', aspect='auto',
                          extent=_extent(img.shape, i, j, *cell))
            elif not head.endswith(PICTURE_ROWS):
                ax.text(j + 0.5, i + 0.5, 'not\nprovided', ha='center',
                        va='center', fontsize=7, color='0.5')
    ax.set_xlim(0, len(cols))  # after imshow, which sets them per image
    ax.set_ylim(len(rows), 0)


# Inches of the strip a colour bar and its label take at the figure's foot.
BAR_STRIP = 0.9


def _difference_bar(fig, base, left):
    """The difference images' colour bar, labelled with its unit, in a
    strip BAR_STRIP inches high `base` inches above the foot of the
    figure, `left` inches from its left edge."""
    h, w = fig.get_figheight(), fig.get_figwidth()
    cax = fig.add_axes((left / w, (base + 0.62 * BAR_STRIP) / h,
                        min(0.9 - left / w, 4.0 / w), 0.12 / h))
    bar = fig.colorbar(plt.cm.ScalarMappable(
        Normalize(-DIFF_LIMIT, DIFF_LIMIT), DIFF_MAP), cax=cax,
        orientation='horizontal', extend='both')
    bar.set_label(f'difference: method − the same renderer\'s ground truth\n'
                  f'({FRACTION}); saturates at ±{DIFF_LIMIT:g}; grey: no '
                  'object', fontsize=8)
    bar.ax.tick_params(labelsize=8)


def _flip_bar(fig, base, left):
    """The FLIP maps' colour bar, as _difference_bar places its own."""
    h, w = fig.get_figheight(), fig.get_figwidth()
    cax = fig.add_axes((left / w, (base + 0.62 * BAR_STRIP) / h,
                        min(0.9 - left / w, 4.0 / w), 0.12 / h))
    bar = fig.colorbar(plt.cm.ScalarMappable(Normalize(0, 1), 'magma'),
                       cax=cax, orientation='horizontal')
    bar.set_label('HDR-FLIP against the same renderer\'s ground truth\n'
                  '(0 no visible difference; 67.02 pixels per degree)',
                  fontsize=8)
    bar.ax.tick_params(labelsize=8)


def grid_fig(var, out, src, renderers, methods=None, width=None):
    """The grid of the given methods (every method, in bands, when None)
    as a Figure, or None when the variant has no images; `width` (inches,
    the paper style's column) scales the cells to fit it exactly, without
    the title (a paper's caption names the variant)."""
    cols, rows = _cells(var, renderers, methods)
    if not rows:
        return None
    parts = bands(cols, rows) if methods is None else [(cols, rows)]
    diffs = any(h.endswith('difference') for _, rs in parts for h, _ in rs)
    flips = any(h.endswith('FLIP') for _, rs in parts for h, _ in rs)
    nc = max(len(c) for c, _ in parts)
    head = HEAD_W if width is None else 0.3
    cw = CELL_W if width is None else (width - head) / nc
    ch = cw * CELL_H / CELL_W
    title = 0.5 if width is None else 0.0
    # A band: its rows and, above them, its column heads (two lines).
    heights = [ch * len(rs) + _head_height(bc, cw) for bc, rs in parts]
    bottom = BAR_STRIP * (diffs + flips)
    fig = plt.figure(figsize=(cw * nc + head, sum(heights) + bottom + title))
    fw, fh = fig.get_figwidth(), fig.get_figheight()
    top = fh - title
    # One axes in cell units per band: an axes per cell costs seconds per
    # variant (each builds its own ticks).
    for (bc, rs), hb in zip(parts, heights):
        top -= hb
        ax = fig.add_axes((head / fw, (top + 0.02) / fh,
                           cw * len(bc) / fw, ch * len(rs) / fh))
        _draw_band(ax, var, out, src, bc, rs, (cw, ch))
    if diffs:
        _difference_bar(fig, BAR_STRIP * flips, head)
    if flips:
        _flip_bar(fig, 0.0, head)
    if width is None:
        fig.suptitle(str(var.get('label', var.get('id'))), fontsize=9,
                     wrap=True, va='bottom', y=(fh - 0.45) / fh)
    return fig


def grid_figure(var, out, src, renderers, figdir, methods):
    """figures/grid-<variant>.{png,pdf} of the given methods; returns the
    paths written ([] when the variant has no images). Every method's
    grid is the page's (in bands, HTML) or `report.py figure --kind grid
    --methods all`."""
    fig = grid_fig(var, out, src, renderers, methods)
    if fig is None:
        return []
    return save(fig, figdir, 'grid-' + stem(var.get('id')), ('png', 'pdf'))
