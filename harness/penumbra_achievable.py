"""The "What is achievable" pictures: `penumbra fit`'s fit.json (docs/
achievable.md), read and checked, and its two figures.

  achievable-share    each method's share of the achievable improvement,
                      (E_none - E_method) / (E_none - E_floor), a point with
                      its 95 % interval, sorted, tie groups banded
  achievable-contour  the study floor's G* over (light angle, deviation)
                      beside chiang2019, estevez2019 and the fitted table
                      (Chiang et al. 2019, Fig. 5), and below each its
                      difference from G*

fit.json has no "format" key (penumbra fit writes none), so it is checked
key by key: a missing key or a wrong shape is BadInput(file, 'JSON
pointer: expected ...'), before anything is drawn.
"""
import json
import math
import os

import numpy as np

from penumbra_contour import contour_panel
from penumbra_data import BadInput, num
from penumbra_paper_figures import interval_points, mark_groups, wrapped
from penumbra_plot import plt, save
from penumbra_style import SCREEN, series_styles

FIT_FILE = os.path.join('fit', 'fit.json')   # inside a study folder
# The methods the contour figure sets beside G*, in this order, when
# fit.json's pictures hold them.
CONTOUR_METHODS = ('chiang2019', 'estevez2019', 'fitted')
# A method that sees more than the floor's inputs (light, deviation): its
# share is not bounded by 1 (docs/achievable.md, "Each method's share").
MORE_INPUTS = {'chiang2019': '⟨Ns,ωi⟩'}
# fit.json's inputs (core/factor_table.h's names) in words.
INPUT_WORDS = {'light': 'light angle', 'deviation': 'deviation',
               'shading': 'shading angle', 'view': 'view angle'}


class Checker:
    """Reads values at JSON pointers of one document, raising BadInput
    naming the file and the pointer."""

    def __init__(self, src, doc):
        self.src, self.doc = src, doc

    def fail(self, ptr, what):
        raise BadInput(self.src, f'{ptr or "/"}: expected {what}')

    def get(self, parent, ptr, key, kinds, what):
        """parent[key], of one of the given types (bool is no number)."""
        p = f'{ptr}/{key}'
        if not isinstance(parent, dict) or key not in parent:
            self.fail(p, what + ' (missing)')
        v = parent[key]
        if not isinstance(v, kinds) or isinstance(v, bool):
            self.fail(p, what)
        return v

    def interval(self, parent, ptr, key):
        """[value, low, high]: a number and two numbers or nulls."""
        v = self.get(parent, ptr, key, list, '[value, low, high]')
        if len(v) != 3 or num(v[0]) != num(v[0]) or any(
                x is not None and num(x) != num(x) for x in v[1:]):
            self.fail(f'{ptr}/{key}', '[value, low, high] of numbers '
                      '(low and high may be null)')
        return [num(x) for x in v]

    def paired(self, parent, ptr, key):
        """{"difference": [value, low, high], "tie": bool}: a paired
        difference of two pooled errors over the same resamples."""
        v = self.get(parent, ptr, key, dict,
                     '{"difference": [value, low, high], "tie": true or '
                     'false} (a fit.json from before paired differences: '
                     'run penumbra fit STUDY again)')
        tie = v.get('tie')
        if not isinstance(tie, bool):
            self.fail(f'{ptr}/{key}/tie', 'true or false')
        return {'difference': self.interval(v, f'{ptr}/{key}', 'difference'),
                'tie': tie}

    def array(self, parent, ptr, key):
        """The objects of parent[key] with their pointers."""
        v = self.get(parent, ptr, key, list, 'an array')
        for i, e in enumerate(v):
            if not isinstance(e, dict):
                self.fail(f'{ptr}/{key}/{i}', 'an object')
        return [(e, f'{ptr}/{key}/{i}') for i, e in enumerate(v)]


def load_fit(path):
    """fit.json, checked (see the module's docstring): a dict of the keys
    the section and the figures read, numbers as floats (nan for null)."""
    try:
        with open(path, encoding='utf-8') as f:
            doc = json.load(f)
    except FileNotFoundError:
        raise BadInput(path, 'no such file (penumbra fit STUDY writes it)')
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise BadInput(path, f'malformed JSON: {e}')
    c = Checker(path, doc)
    if not isinstance(doc, dict):
        c.fail('', 'an object')
    floor = c.get(doc, '', 'floor', dict, 'an object')
    fit = {'src': path, 'unit': c.get(doc, '', 'unit', str, 'a string'),
           'variants': c.get(doc, '', 'variants', int, 'an integer'),
           # absent before fit.json's contents 4: none left out
           'unconverged_truths': [
               e if isinstance(e, str)
               else c.fail(f'/unconverged_truths/{i}', 'a variant id (a string)')
               for i, e in enumerate(
                   c.get(doc, '', 'unconverged_truths', list, 'an array')
                   if 'unconverged_truths' in doc else [])],
           'floor': floor_of(c, floor, '/floor'),
           'families': [floor_of(c, e, p)
                        for e, p in c.array(doc, '', 'family_floors')],
           'methods': [method_of(c, e, p)
                       for e, p in c.array(doc, '', 'methods')],
           'held_out': [held_out_of(c, e, p)
                        for e, p in c.array(doc, '', 'held_out')],
           # null with no family held out (a study of one scene family)
           'held_out_pooled': (None if doc.get('held_out_pooled', 0) is None
                               and not doc.get('held_out')
                               else c.interval(doc, '', 'held_out_pooled')),
           # null without a shipped method or without held-out families
           'best_method': (None if doc.get('best_method', 0) is None
                           else c.get(doc, '', 'best_method', str,
                                      'a string or null')),
           'held_out_minus_best': (
               None if doc.get('held_out_minus_best', 0) is None
               and (not doc.get('held_out') or doc.get('best_method') is None)
               else c.paired(doc, '', 'held_out_minus_best')),
           'constants': [constant_of(c, e, p)
                         for e, p in c.array(doc, '', 'constants')],
           # absent before fit.json's contents 8: no offset refitted
           'offset_parameters': [offset_parameter_of(c, e, p)
                                 for e, p in (
                                     c.array(doc, '', 'offset_parameters')
                                     if 'offset_parameters' in doc else [])],
           # absent before fit.json's contents 5: light,deviation, none nested
           'inputs': (c.get(doc, '', 'inputs', str, 'a string')
                      if 'inputs' in doc else 'light,deviation'),
           'nested': [nested_of(c, e, p)
                      for e, p in (c.array(doc, '', 'nested_floors')
                                   if 'nested_floors' in doc else [])],
           # absent before fit.json's contents 7: no image floors
           'image': (image_floors_of(c, doc['image_floor'], '/image_floor')
                     if 'image_floor' in doc else None),
           'pictures': None}
    # null: a grid other than light,deviation (no contour to draw)
    if doc.get('pictures') is not None:
        fit['pictures'] = pictures_of(c, doc['pictures'], '/pictures')
    return fit


def floor_of(c, e, p):
    return {'scope': c.get(e, p, 'scope', str, 'a string'),
            'variants': c.get(e, p, 'variants', int, 'an integer'),
            'floor': c.interval(e, p, 'floor'),
            'none': c.interval(e, p, 'none')}


def image_floors_of(c, e, p):
    """The image RMSE's per-variant floors pooled, raw bump's image RMSE,
    and each method's image RMSE and share of the floors' gain."""
    if not isinstance(e, dict):
        c.fail(p, 'an object')
    return {'unit': c.get(e, p, 'unit', str, 'a string'),
            'floor': c.interval(e, p, 'floor'),
            'none': c.interval(e, p, 'none'),
            'methods': [method_of(c, m, q)
                        for m, q in c.array(e, p, 'methods')]}


def nested_of(c, e, p):
    """A floor of fewer inputs on the fit's own grid, and the fit's floor
    minus it, paired."""
    f = floor_of(c, e, p)
    f['inputs'] = c.get(e, p, 'inputs', str, 'a string')
    f['gain'] = c.paired(e, p, 'gain')
    return f


def inputs_text(inputs):
    """'light,deviation,shading' as words: 'light angle, deviation and
    shading angle'."""
    words = [INPUT_WORDS.get(i, i) for i in inputs.split(',')]
    return ', '.join(words[:-1]) + ' and ' + words[-1] if len(words) > 1 \
        else words[0]


def method_of(c, e, p):
    return {'method': c.get(e, p, 'method', str, 'a string'),
            'error': c.interval(e, p, 'error'),
            'share': c.interval(e, p, 'share'),
            # null where the share is undefined (not in any group)
            'group': (None if e.get('group', 0) is None
                      else c.get(e, p, 'group', int, 'an integer or null')),
            'leader': (None if e.get('group', 0) is None
                       else c.get(e, p, 'leader', str, 'a string')),
            'versus_leader': (None if e.get('group', 0) is None
                              else c.paired(e, p, 'versus_leader')),
            'on_grid': 'on_grid' in e}


def held_out_of(c, e, p):
    return {'family': c.get(e, p, 'family', str, 'a string'),
            'variants': c.get(e, p, 'variants', int, 'an integer'),
            'held_out': c.interval(e, p, 'held_out'),
            'in_sample': num(c.get(e, p, 'in_sample_floor', (int, float),
                                   'a number')),
            'none': c.interval(e, p, 'none'),
            'best_method': c.get(e, p, 'best_method', str, 'a string'),
            'best': c.interval(e, p, 'best'),
            # null where the family has no shipped method
            'held_out_minus_best': (
                None if e.get('held_out_minus_best', 0) is None
                and not e.get('best_method')
                else c.paired(e, p, 'held_out_minus_best'))}


def offset_parameter_of(c, e, p):
    """A low-poly offset's parameter refitted among the rendered values:
    the fields a constant has (constant_of), its values with their errors
    and the variants it was fitted on."""
    out = constant_of(c, {**e, 'method': c.get(e, p, 'offset', str,
                                               'a string'),
                          'constant': c.get(e, p, 'parameter', str,
                                            'a string')}, p)
    out['variants'] = c.get(e, p, 'variants', int, 'an integer')
    out['values'] = [
        {'value': num(c.get(v, q, 'value', (int, float), 'a number')),
         'error': c.interval(v, q, 'error')}
        for v, q in c.array(e, p, 'values')]
    return out


def is_null(e, key):
    """Whether e holds key, as null."""
    return key in e and e[key] is None


def constant_of(c, e, p):
    def number(k):
        return num(c.get(e, p, k, (int, float), 'a number'))
    return {'method': c.get(e, p, 'method', str, 'a string'),
            'constant': c.get(e, p, 'constant', str, 'a string'),
            'published': number('published'),
            # absent before fit.json's contents 6: every one published
            'reference': (c.get(e, p, 'reference', str, 'a string')
                          if 'reference' in e else 'published'),
            # null or absent: fitted through the grid, or no render to match
            'probe_minus_rendered': (
                num(c.get(e, p, 'probe_minus_rendered', (int, float),
                          'a number or null'))
                if e.get('probe_minus_rendered') is not None else None),
            'fitted': c.interval(e, p, 'fitted'),
            'error_published': c.interval(e, p, 'error_published'),
            'error_in_sample': c.interval(e, p, 'error_fitted_in_sample'),
            # null (present) where the variants are of one family: nothing
            # to fit on once it is held out; absent is an old fit.json
            'error_held_out': (None if is_null(e, 'error_fitted_held_out')
                               else c.interval(e, p, 'error_fitted_held_out')),
            'held_out_minus_published': (
                None if is_null(e, 'held_out_minus_published')
                else c.paired(e, p, 'held_out_minus_published')),
            # null or absent (a fit.json before it): inside the range
            'at_bound': (c.get(e, p, 'at_bound', str, 'a string or null')
                         if e.get('at_bound') is not None else None)}


def pictures_of(c, pic, p):
    """{'light', 'deviation', 'g': {name: G[deviation][light]}, 'note'}:
    the axes increasing, each G len(deviation) rows of len(light) numbers
    or nulls (nan), `floor` among them."""
    axes = {}
    for key in ('light_deg', 'deviation_deg'):
        a = c.get(pic, p, key, list, 'an array of increasing numbers')
        v = np.array([num(x) for x in a], dtype=float)
        if v.size < 2 or not np.all(np.diff(v) > 0):
            c.fail(f'{p}/{key}', '>= 2 increasing numbers')
        axes[key] = v
    L, D = axes['light_deg'], axes['deviation_deg']
    g = c.get(pic, p, 'g', dict, 'an object of tables')
    c.get(g, f'{p}/g', 'floor', list, f'{D.size} rows of {L.size} numbers')
    tables = {}
    for name, rows in g.items():
        q = f'{p}/g/{name}'
        if not isinstance(rows, list) or len(rows) != D.size or any(
                not isinstance(r, list) or len(r) != L.size or any(
                    x is not None and num(x) != num(x) for x in r)
                for r in rows):
            c.fail(q, f'{D.size} rows (deviation) of {L.size} numbers or '
                   'nulls (light angle)')
        tables[name] = np.array([[num(x) for x in r] for r in rows])
    note = pic.get('note')
    return {'light': L, 'deviation': D, 'g': tables,
            'note': note if isinstance(note, str) else ''}


def fit_path(study):
    return os.path.join(study, FIT_FILE)


def share_groups(methods):
    """Methods in fit.json's tie groups by share (each group's leader the
    highest share not yet grouped; a member's share minus the leader's,
    paired over the same resamples, holds 0), by group, then share, highest
    first. [{'method', 'group', 'leader', 'value', 'lo', 'hi'}]."""
    rows = sorted((m for m in methods if m['group'] is not None),
                  key=lambda m: (m['group'], -m['share'][0], m['method']))
    return [{'method': m['method'], 'group': m['group'],
             'leader': m['leader'], 'value': m['share'][0],
             'lo': m['share'][1], 'hi': m['share'][2]} for m in rows]


def more_inputs(fit):
    """The methods that see an input the fit's grid lacks, with it."""
    inputs = fit['inputs'].split(',')
    return {m: w for m, w in MORE_INPUTS.items() if 'shading' not in inputs}


def share_caption(fit):
    more = ', '.join(f'{m} (also sees {w})'
                     for m, w in more_inputs(fit).items())
    return (f'Each method\'s share of the achievable improvement, '
            f'(E_none − E_method) / (E_none − E_floor) (fraction; 0: raw '
            f'bump, dashed; 1: the study floor, the lowest pooled '
            f'terminator-profile RMSE of any factor G of the '
            f'{inputs_text(fit["inputs"])} on the grid, dotted), over '
            f'{fit["variants"]} '
            'variants; bars: 95 % percentile bootstrap over variants. '
            'Bands: tie groups, in order: the highest share not yet '
            'grouped leads the next group, which holds every lower one '
            'whose share minus the leader\'s, paired over the same '
            'resamples, has a 95 % interval holding 0. '
            + (f'† not bounded by 1: {more}; methods' if more else 'Methods')
            + ' that are not factors of these inputs (microfacet, '
            'adjustment) are not bounded by 1.')


def share_fig(fit, style):
    """The share chart (see share_caption); None without shares."""
    placed = share_groups(fit['methods'])
    if not placed:
        return None
    y, last = 0.0, None
    for p in placed:
        if last is not None and p['group'] != last:
            y += 0.6
        p['y'], last, y = y, p['group'], y + 1
    span = placed[-1]['y'] + 1
    fig, ax = plt.subplots(figsize=(style.width(6.4), 1.6 + 0.15 * span
                                    if style.paper else 2.0 + 0.24 * span),
                           layout='constrained')
    ends = [v for p in placed for v in (p['lo'], p['hi'], p['value'])
            if math.isfinite(v)] + [0.0, 1.0]
    pad = 0.04 * (max(ends) - min(ends))
    lim = (min(ends) - pad, max(ends) + pad)
    mark_groups(ax, placed)
    ax.axvline(0.0, color='0.3', lw=0.8, ls='--', zorder=1)
    ax.axvline(1.0, color='0.3', lw=0.8, ls=':', zorder=1)
    styles = series_styles(m['method'] for m in fit['methods'])
    interval_points(ax, placed, styles, lim)
    ax.set_yticks([p['y'] for p in placed],
                  [p['method'] + (' †' if p['method'] in more_inputs(fit) else '')
                   for p in placed])
    ax.set_ylim(placed[-1]['y'] + 0.7, -0.7)
    ax.set_xlabel('share of the achievable improvement on raw bump\n'
                  '(fraction; 0 raw bump, 1 the study floor)')
    ax.grid(axis='x', alpha=0.3)
    fig.supxlabel(wrapped(fig, share_caption(fit), 7), fontsize=7,
                  ha='center')
    return fig


def contour_fig(fit, style):
    """G* and the methods beside it (top row), each one's difference from
    G* below it on one symmetric scale; None without fit.json's
    pictures."""
    pic = fit['pictures']
    if pic is None:
        return None
    L, D, g = pic['light'], pic['deviation'], pic['g']
    names = [m for m in CONTOUR_METHODS if m in g] + sorted(
        m for m in g if m != 'floor' and m not in CONTOUR_METHODS)
    cols = 1 + len(names)
    fig, axs = plt.subplots(2, cols, squeeze=False, layout='constrained',
                            figsize=style.size(3.6 * cols + 1, 7.6))
    top = max([2.0] + [float(np.nanmax(t)) for t in g.values()
                       if np.isfinite(t).any()])
    levels = np.linspace(0, math.ceil(top * 2) / 2, 2 * int(
        math.ceil(top * 2)) + 1)
    # Labelled lines at 0.5 and 1 only: G* is fitted cell by cell and
    # noisy, and a line at every level would bury it in labels.
    im = contour_panel(axs[0][0], L, D, g['floor'], 'G*: the study floor',
                       levels=levels, lines=[0.5, 1.0])
    for ax, m in zip(axs[0][1:], names):
        contour_panel(ax, L, D, g[m], m, levels=levels, lines=[0.5, 1.0])
    fig.colorbar(im, ax=axs[0].tolist(), label='G (1: raw bump)')
    diffs = {m: g[m] - g['floor'] for m in names}
    lim = max([float(np.nanmax(np.abs(d))) for d in diffs.values()
               if np.isfinite(d).any()] + [1e-3])
    axs[1][0].axis('off')
    for ax, m in zip(axs[1][1:], names):
        im = contour_panel(ax, L, D, diffs[m], f'{m} − G*', lim,
                           lines=[0.0])
    if names:
        fig.colorbar(im, ax=axs[1].tolist(), label='G − G*')
    outer_labels(axs)
    fig.supxlabel(wrapped(fig, contour_note(pic), 7), fontsize=7)
    return fig


def outer_labels(axs):
    """Axis labels on the outer panels only, and no legend (the caption
    says what the dashed line is): contour_panel labels every panel, which
    a row of four panels a page wide has no room for."""
    for (r, k), ax in np.ndenumerate(axs):
        if not ax.axison:
            continue
        below = r + 1 < len(axs) and axs[r + 1][k].axison
        left = k > 0 and axs[r][k - 1].axison
        ax.set_xlabel('' if below else 'light angle from Ng (°)')
        ax.set_ylabel('' if left else 'deviation (°)')
        if ax.get_legend() is not None:
            ax.get_legend().remove()


def contour_note(pic):
    return ('Top: G, the fraction of raw bump\'s direct light a factor '
            'lets through, of the study floor G* and of each method; '
            'bottom: each one\'s difference from G* (blue: more light '
            'than G*, red: less). Axes: the light\'s angle from Ng and '
            'the shading normal\'s deviation from Ng towards the light, '
            'degrees; dashed: y = x, the shading normal points at the '
            'light. Blank: cells no variant lights (G* undefined). '
            + pic['note'])


def load_study_fit(study):
    """STUDY/fit/fit.json checked, or None when the study has none."""
    path = fit_path(study)
    return load_fit(path) if os.path.exists(path) else None


def achievable_figures(fit, figdir):
    """figures/achievable-share.* and achievable-contour.* of a study's
    fit (each where it has data): {'fit', 'share', 'contour' (the PNGs or
    None), 'written'}."""
    out = {'fit': fit, 'share': None, 'contour': None, 'written': []}
    if fit is None:
        return out
    for key, draw in (('share', share_fig), ('contour', contour_fig)):
        with SCREEN.active():
            fig = draw(fit, SCREEN)
        if fig is not None:
            paths = save(fig, figdir, f'achievable-{key}')
            out[key], out['written'] = paths[0], out['written'] + paths
    return out
