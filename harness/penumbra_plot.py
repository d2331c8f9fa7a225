"""Matplotlib set-up and helpers shared by every Penumbra figure module.

Importing this module selects the Agg backend (no display) and the rcParams
that make the output reproducible: the same input gives the same bytes,
with no dates or versions in the files and a fixed SVG hash salt.
"""
import contextlib
import math
import multiprocessing
import os
import sys
import tempfile
import textwrap

import matplotlib
import numpy as np
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.font_manager import FontProperties  # noqa: E402

plt.rcParams.update({'svg.hashsalt': 'penumbra', 'font.size': 10,
                     'axes.titlesize': 11, 'legend.fontsize': 8})
META = {'png': {'Software': None}, 'svg': {'Date': None, 'Creator': None},
        'pdf': {'CreationDate': None, 'Creator': None, 'Producer': None}}


def save(fig, outdir, name, formats=tuple(META)):
    """Write fig as outdir/name.<format> for each of formats (PNG, SVG and
    PDF by default); returns the paths, in that order.

    The layout and the tight bounding box are found once, by a draw
    without output, and every format reuses them: savefig's 'tight' would
    lay out and measure the figure again for each format (the figures of
    the default study: 84-91 s -> 70-75 s of wall time on 2 cores)."""
    fig.draw_without_rendering()
    bbox = fig.get_tightbbox().padded(0.05)
    fig.set_layout_engine('none')
    written = []
    try:
        for ext in formats:
            path = os.path.join(outdir, f'{name}.{ext}')
            with replacing(path) as tmp:
                fig.savefig(tmp, format=ext, dpi=150 if ext == 'png' else 72,
                            metadata=META[ext], bbox_inches=bbox)
            written.append(path)
    finally:
        plt.close(fig)
    return written


# What replacing() names its temporary files: the C++ side removes those a
# killed script left (study/figures.cpp).
TEMPORARY_PREFIX = '.penumbra-draw-'


@contextlib.contextmanager
def replacing(path):
    """A temporary name beside path to write to, renamed over path when
    the block ends without an error and removed otherwise: a full disk
    leaves no half-written file under path's name."""
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=TEMPORARY_PREFIX,
                               suffix=os.path.splitext(path)[1], dir=folder)
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def fitted_title(fig, text):
    """text broken into lines no wider than the figure, for suptitle:
    matplotlib's wrap=True does not hold under a tight bounding box, which
    grows to the whole line (a profile figure was 20 inches wide for a
    6.8-inch plot). 0.55 em is a generous mean width of DejaVu Sans."""
    size = FontProperties(size=plt.rcParams['figure.titlesize'])
    chars = max(30, int(fig.get_figwidth() * 72 / (0.55 * size.get_size_in_points())))
    return '\n'.join(textwrap.wrap(text, chars)) or text


def progress(text):
    """One progress line on stderr, which the C++ side forwards to the
    user while the figures are drawn (study/figures.cpp)."""
    print(f'progress: {text}', file=sys.stderr, flush=True)


class _Serial:
    """A pool of none: imap in this process (one task, or one core)."""
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    @staticmethod
    def imap(func, tasks):
        return map(func, tasks)


def worker_pool(tasks):
    """Processes for independent figures, one per core this process may use
    (at most one per task); results come back in task order, so the output
    and its order do not depend on the number of cores. Forked: the workers
    inherit the Agg set-up above."""
    cores = len(os.sched_getaffinity(0))
    if min(cores, tasks) < 2:
        return _Serial()
    return multiprocessing.get_context('fork').Pool(min(cores, tasks))


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
