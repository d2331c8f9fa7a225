"""The look of every figure: two styles, and the palette of the series.

  screen  the report page's look (the default): 10-pt text, figures as wide
          as their content needs, cropped to what was drawn.
  paper   a journal's: 8-pt text (7-pt ticks and legends), figures exactly
          3.5 in (one column) or 7 in (two columns) wide, vector PDF with
          TrueType fonts embedded (pdf.fonttype 42, which journals' checks
          accept, where Type 3 fonts are refused).

Both keep penumbra_plot's reproducibility settings (no dates, fixed SVG hash
salt): the same input gives the same bytes.

The palette tells up to 63 series apart by colour AND line style AND marker:
nine colours (tab10 without its grey, which `none` has), four dash patterns
and seven markers. The k-th method gets colour k mod 9, dash (k // 9) mod 4
and marker k mod 7; as 9 and 7 share no factor, (colour, marker) differs for
any two of the first 63 methods, and (colour, dash) for the first 36. A
method's style depends only on its place in the report's method list (the
order the study names them), so it is the same in every figure.
"""
import contextlib
import os

from penumbra_plot import META, plt, replacing

WIDTHS = {1: 3.5, 2: 7.0}          # inches: one and two journal columns
STYLES = {
    'screen': {'font.size': 10, 'axes.titlesize': 11, 'legend.fontsize': 8},
    'paper': {'font.size': 8, 'axes.titlesize': 8, 'axes.labelsize': 8,
              'xtick.labelsize': 7, 'ytick.labelsize': 7,
              'legend.fontsize': 7, 'figure.titlesize': 9,
              'lines.linewidth': 1.0, 'lines.markersize': 3.5,
              'axes.linewidth': 0.6, 'errorbar.capsize': 2,
              'pdf.fonttype': 42, 'ps.fonttype': 42}}
MIN_TEXT_PT = 7                    # no text in a paper figure is smaller

GREY = (0.5, 0.5, 0.5)
COLOURS = [c for i, c in enumerate(plt.get_cmap('tab10').colors) if i != 7]
DASHES = ['-', (0, (5, 2)), (0, (1, 1.2)), (0, (6, 1.5, 1, 1.5))]
MARKERS = ['o', 's', '^', 'D', 'v', 'P', 'X']


def series_styles(names):
    """{name: {'color', 'ls', 'marker'}} in order of first appearance;
    'none' (raw bump, the baseline) grey, solid, without marker."""
    styles = {'none': {'color': GREY, 'ls': '-', 'marker': ''}}
    k = 0
    for name in names:
        if name in styles:
            continue
        styles[name] = {'color': COLOURS[k % len(COLOURS)],
                        'ls': DASHES[(k // len(COLOURS)) % len(DASHES)],
                        'marker': MARKERS[k % len(MARKERS)]}
        k += 1
    return styles


def method_colors(names):
    """The colours alone of series_styles (figures whose series differ by
    colour and their own markers or dashes)."""
    return {k: v['color'] for k, v in series_styles(names).items()}


class Style:
    """A style and, for paper, the column count it sizes figures for."""

    def __init__(self, name='screen', columns=2):
        if name not in STYLES:
            raise ValueError(f'unknown style {name!r}')
        self.name, self.columns = name, columns
        self.paper = name == 'paper'

    def width(self, screen_width):
        """The figure width: the journal column's on paper, else the
        screen figure's own."""
        return WIDTHS[self.columns] if self.paper else screen_width

    def size(self, screen_width, height):
        """(width, height) in inches; on paper the height shrinks with the
        width, by at most half, so a one-column figure keeps its panels'
        shape without growing taller than a page allows."""
        if not self.paper:
            return screen_width, height
        w = WIDTHS[self.columns]
        return w, max(height * min(1.0, w / screen_width), height * 0.5)

    @contextlib.contextmanager
    def active(self):
        """rcParams of this style while a figure is built."""
        with plt.rc_context(STYLES[self.name]):
            yield self


def write_figure(fig, path, style):
    """One figure into path (.pdf, .svg or .png, by its extension),
    atomically: a reader never sees half a file, and an error leaves
    nothing. On paper the page is the figure's exact size (no cropping:
    the size is the column's); on screen it is cropped to what was
    drawn, as in the report."""
    ext = os.path.splitext(path)[1][1:].lower()
    try:
        with replacing(path) as tmp, plt.rc_context(STYLES[style.name]):
            fig.savefig(tmp, format=ext, metadata=META[ext],
                        dpi=(300 if style.paper else 150) if ext == 'png'
                        else 72, bbox_inches=None if style.paper else 'tight',
                        pad_inches=0.05)
    finally:
        plt.close(fig)
    return path


SCREEN = Style('screen')
