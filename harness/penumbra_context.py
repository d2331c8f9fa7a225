"""Building blocks of report.html's template context.

Plain dicts the templates (templates/macros.html.j2) know how to draw:
  table   {'head': [str], 'rows': [[cell]], 'row_class': str}
  cell    {'text': str, 'cls': str}  (cls: '', 'n' right-aligned number,
          'n na' greyed n/a, 'na' greyed text)
  figure  {'src': URL or data: URI, 'alt': str, 'caption': str ('' for none)}
  grid    {'cols': [str], 'rows': [{'head': str, 'cells': [grid cell]}]}
  grid cell {'figure': figure or None, 'na': str or None} (both None: an
          empty cell)
Every str is plain text: the template escapes it.
"""
import math

from penumbra_data import data_uri, fmt, num


def cell(c):
    """A table cell: strings as they are; ints as they are, right-aligned;
    anything else a number formatted by fmt (a (value, scale) tuple is
    scaled), right-aligned, greyed when n/a; a dict is a cell already."""
    if isinstance(c, dict):
        return c
    if isinstance(c, str) or type(c) is int:
        return {'text': str(c), 'cls': 'n' if type(c) is int else ''}
    t = fmt(*c) if isinstance(c, tuple) else fmt(c)
    return {'text': t, 'cls': 'n na' if t == 'n/a' else 'n'}


def table(head, rows, row_class=''):
    return {'head': [str(h) for h in head],
            'rows': [[cell(c) for c in r] for r in rows],
            'row_class': row_class}


def figure(src, alt, caption=''):
    return {'src': src, 'alt': str(alt), 'caption': str(caption)}


def figure_file(path, alt, caption):
    """A figure drawn by the figure modules, embedded."""
    return figure(data_uri(path, path, 'figure'), alt, caption)


def grid_cell(fig=None, na=None):
    return {'figure': fig, 'na': na}


def interval_text(ci, scale=1.0, digits=2):
    """'[lo, hi]' of a report.json interval pair (n/a when undefined)."""
    if not isinstance(ci, list) or len(ci) != 2 or None in ci:
        return 'n/a'
    lo, hi = (float(v) * scale for v in ci)
    return f'[{lo:.{digits}f}, {hi:.{digits}f}]'


def ci_cell(value, ci, scale=100.0, digits=1):
    """A right-aligned 'value [lo, hi]' cell, scaled (100: percent), with
    at least `digits` decimals and more when the numbers are small, so that
    the largest shows two significant digits (0.0012, not 0.00)."""
    v = num(value)
    if not math.isfinite(v):
        return {'text': 'n/a', 'cls': 'n na'}
    ends = [num(t) for t in ci] if isinstance(ci, list) else []
    big = max(abs(t * scale) for t in [v] + ends if math.isfinite(t))
    if big > 0:
        digits = min(max(digits, 1 - math.floor(math.log10(big))), 5)
    # An interval that excludes 0 must not show an end of 0.000: it would
    # read as a tie.
    if len(ends) == 2 and all(map(math.isfinite, ends)) and (
            ends[0] > 0 or ends[1] < 0):
        near = min(abs(t * scale) for t in ends)
        while digits < 5 and round(near, digits) == 0:
            digits += 1
    return {'text': f'{v * scale:.{digits}f} {interval_text(ci, scale, digits)}',
            'cls': 'n'}
