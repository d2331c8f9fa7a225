"""Reading and checking a Penumbra study's report.json.

Shared by the figure modules and the HTML page: the JSON helpers (every
value read defensively, since the file is input), the path checks that keep
every image named in the JSON inside the output folder, the number format
of the tables and tick labels, and the low-poly section's model (variants
and comparisons placed in groups and tessellation levels). Nothing here
draws or writes; nothing from the JSON is executed.
"""
import base64
import json
import math
import os
import re
import urllib.parse

import numpy as np

REF = 'evaluator'                 # the renderer whose displacement is truth
LP_TRUTH = 'analytic'             # low-poly: the untessellated surface
FRACTION = 'fraction of albedo·E/π'
GROUND_TRUTH = 'ground truth (displacement)'
PRIMARY = 'combined_relative_error'   # the one ranking metric (issue 37)
COMBINED_UNIT = "fraction of raw bump's E_term + E_view in the same variant"
METRICS = {                       # metric -> (name, unit)
    PRIMARY: ('combined error C', COMBINED_UNIT),
    'profile.rmse_terminator': ('terminator-region profile RMSE', FRACTION),
    'profile.rmse_overall': ('profile RMSE, all bins', FRACTION),
    'profile.max_error_terminator': ('max terminator error', FRACTION),
    'profile.max_step': ('largest profile step', FRACTION),
    'profile.position_error_deg': ('terminator position error', 'degrees'),
    'profile.width_deg': ('terminator width', 'degrees'),
    'profile.lit_bias': ('lit-region bias', FRACTION),
    'view.rmse_grazing': ('grazing-view RMSE', FRACTION),
    'view.bias_grazing': ('grazing-view bias', FRACTION),
    'image.rmse': ('image RMSE', 'W m⁻² sr⁻¹'),
    'image.ssim': ('image SSIM', 'unitless, [-1, 1]'),
    'image.flip': ('mean HDR-FLIP', 'unitless, [0, 1]'),
    'image.mask_iou': ('silhouette IoU', 'unitless, [0, 1]')}
CSV_COLUMNS = {                   # metric -> its metrics.csv column
    PRIMARY: PRIMARY,
    'profile.rmse_terminator': 'profile_rmse_terminator_rel',
    'profile.rmse_overall': 'profile_rmse_overall_rel',
    'profile.max_error_terminator': 'profile_max_error_terminator_rel',
    'profile.max_step': 'profile_max_step_rel',
    'profile.position_error_deg': 'position_error_deg',
    'profile.width_deg': 'transition_width_deg',
    'profile.lit_bias': 'lit_bias_rel',
    'view.rmse_grazing': 'view_rmse_grazing_rel',
    'view.bias_grazing': 'view_bias_grazing_rel',
    'image.rmse': 'image_rmse_w_m2_sr',
    'image.ssim': 'image_ssim',
    'image.flip': 'image_flip',
    'image.mask_iou': 'image_mask_iou'}
# (metric, name, unit, scale): fractions, as lowpoly.csv gives them (its
# column in LP_COLUMNS); the page's low-poly tables say "%" where they
# show percent.
LP_PANELS = (
    ('shadow.darkened_fraction', 'darkened share of the lit pixels',
     'fraction of pixels', 1),
    ('shadow.max_darkening', 'max darkening', FRACTION, 1),
    ('profile.rmse_terminator', 'terminator profile RMSE', FRACTION, 1))
LP_SIDE = (
    ('shadow.lost_shadow_fraction', 'lost share of the analytic cast shadow',
     'fraction of pixels', 1),
    ('shadow.shadow_shift_px', 'cast-shadow shift', 'pixels', 1),
    ('shadow.darkened_fraction', 'darkened share of the lit pixels',
     'fraction of pixels', 1))
LP_COLUMNS = {'shadow.darkened_fraction': 'darkened_fraction',
              'shadow.max_darkening': 'max_darkening_rel',
              'profile.rmse_terminator': 'profile_rmse_terminator_rel',
              'shadow.lost_shadow_fraction': 'lost_shadow_fraction',
              'shadow.shadow_shift_px': 'shadow_shift_px'}

class BadInput(Exception):
    """Bad input: reported as 'report.py: <file>: <what>', exit status 2."""

    def __init__(self, file, what):
        super().__init__(f'{file}: {what}')


def num(x):
    """A JSON number as float; nan for null or anything else."""
    ok = isinstance(x, (int, float)) and not isinstance(x, bool)
    return float(x) if ok else math.nan


def farray(xs):
    return np.array([num(v) for v in (xs if isinstance(xs, list) else [])],
                    dtype=float)


def obj(x):
    return x if isinstance(x, dict) else {}


def objs(x):
    """The objects of a JSON array (anything else: none)."""
    return [e for e in x if isinstance(e, dict)] if isinstance(x, list) else []


def stem(s):
    """A string from the JSON made safe as part of a file name."""
    return re.sub(r'[^A-Za-z0-9_.+-]', '_', str(s)).lstrip('.') or '_'


def metric_label(metric):
    name, unit = METRICS.get(metric, (metric, ''))
    return f'{name} ({unit})' if unit else name


def fmt(x, scale=1.0, digits=3):
    x = num(x)
    return 'n/a' if not math.isfinite(x) else f'{x * scale:.{digits}g}'


def get_metric(comp, metric):
    """comp's value at a dotted path such as 'profile.rmse_terminator'."""
    for key in metric.split('.'):
        comp = obj(comp).get(key)
    return num(comp)


def column(r):
    """The image-grid column of a render (also its label in the figures)."""
    rep, meth = str(r.get('representation')), str(r.get('method'))
    return GROUND_TRUTH if rep == 'displacement' else (
        meth if rep == 'bump' else f'{meth} ({rep})')


def axis_text(v, i):
    """A tick label: numbers as they are, vectors as '#i: (x, y, z)'."""
    if isinstance(v, list):
        return f'#{i}: (' + ', '.join(fmt(t) for t in v) + ')'
    return fmt(v, digits=4) if math.isfinite(num(v)) else str(v)


def axis_labels(axis):
    """The tick texts of an axis of report.json: its value_labels (light
    directions as azimuth and elevation), else axis_text of each value."""
    vals = axis.get('values') if isinstance(axis.get('values'), list) else []
    texts = axis.get('value_labels')
    if isinstance(texts, list) and len(texts) == len(vals) and all(
            isinstance(t, str) for t in texts):
        return texts
    return [axis_text(v, i) for i, v in enumerate(vals)]


def axis_index(values, v):
    def same(a, b):
        if isinstance(a, list) and isinstance(b, list):
            return len(a) == len(b) and all(map(same, a, b))
        fa, fb = num(a), num(b)
        if math.isfinite(fa) and math.isfinite(fb):
            return math.isclose(fa, fb, rel_tol=1e-9, abs_tol=1e-12)
        return a == b
    return next((i for i, a in enumerate(values) if same(a, v)), None)


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
    if obj(data).get('format') != fmt_name:
        raise BadInput(path, f'expected an object with "format": '
                       f'"{fmt_name}"')
    if data.get('version') != 1:
        raise BadInput(path, f'unsupported version {data.get("version")!r} '
                       '(expected 1)')
    return data


def inside(out, rel, src, ctx):
    """The path of a file named in the JSON, checked to lie inside OUT."""
    if not isinstance(rel, str) or not rel:
        raise BadInput(src, f'{ctx}: expected a relative path, got {rel!r}')
    if os.path.isabs(rel) or re.match(r'^[A-Za-z]:', rel) or \
            '..' in re.split(r'[\\/]', rel):
        raise BadInput(src, f'{ctx}: path {rel!r} must be relative and '
                       'inside the output folder (no absolute path, no "..")')
    path = os.path.join(out, rel)
    if not os.path.realpath(path).startswith(os.path.realpath(out) + os.sep):
        raise BadInput(src, f'{ctx}: path {rel!r} leaves the output folder')
    return path


class PageImages:
    """How report.html refers to its images, set once per page (report.py):
    linked by default (a relative URL from OUT: the page stays small and
    sits beside images/ and figures/), or embedded as data: URIs
    (--self-contained: one file to mail, every image inlined)."""
    embed = False
    out = '.'


def data_uri(path, src, ctx):
    """The PNG at path as the page refers to it (PageImages): its URL
    relative to OUT, or a data: URI. Either way the file must exist and be
    a PNG, so that a bad path fails before any figure is drawn."""
    try:
        with open(path, 'rb') as f:
            data = f.read() if PageImages.embed else f.read(8)
    except OSError as e:
        raise BadInput(src, f'{ctx}: {path}: {e.strerror or e}')
    if not data.startswith(b'\x89PNG\r\n\x1a\n'):
        raise BadInput(src, f'{ctx}: {path}: not a PNG file')
    if not PageImages.embed:
        rel = os.path.relpath(path, PageImages.out).replace(os.sep, '/')
        return urllib.parse.quote(rel)
    return 'data:image/png;base64,' + base64.b64encode(data).decode('ascii')


def region(r, default):
    """A [from, to] angle range of the units, or default when malformed."""
    ok = isinstance(r, list) and len(r) == 2 and all(
        math.isfinite(num(t)) for t in r)
    return [float(t) for t in r] if ok else default


# A page with a section (image grid, profile figure, metrics table) per
# variant stays readable up to a few dozen variants; a sweep of 10^4 would
# take hours of plotting and a page no browser opens. Past this many, the
# page shows a balanced selection and says which (penumbra_headline_html);
# every number stays in report.json and metrics.csv.
MAX_VARIANT_SECTIONS = 48


def _levels(v):
    """The (what, value) pairs a variant stands for: its scene and each
    axis' value."""
    av = v.get('axis_values') if isinstance(v.get('axis_values'), list) \
        else []
    return [('scene', str(v.get('scene')))] + [
        (k, json.dumps(a, sort_keys=True)) for k, a in enumerate(av)]


def evenly_spaced(n, k):
    """k indices evenly spaced over range(n), the first and last included."""
    return sorted({round(i * (n - 1) / (k - 1)) for i in range(k)})


def shown_variants(variants, limit=MAX_VARIANT_SECTIONS):
    """The variants that get a section of their own, in study order: all
    up to `limit`, else a balanced pick: each pick the variant whose scene
    and axis values have been picked least so far (summed); on a tie, the
    first of the evenly spaced variants (first and last included), then
    the others in study order. Evenly spaced picks alone skipped a whole
    amplitude of the default study (72 variants, 48 sections: every
    A = 0.01 variant); this gives each scene and each axis value its
    share, and is the evenly spaced pick where every variant has values of
    its own (one axis)."""
    n = len(variants)
    if n <= limit:
        return list(variants)
    even = evenly_spaced(n, limit)
    priority = {i: r for r, i in enumerate(
        even + [i for i in range(n) if i not in set(even)])}
    keys = [_levels(v) for v in variants]
    counts, picked = {}, [False] * n
    for _ in range(limit):
        best = min((i for i in range(n) if not picked[i]), key=lambda i: (
            sum(counts.get(k, 0) for k in keys[i]), priority[i]))
        picked[best] = True
        for k in keys[best]:
            counts[k] = counts.get(k, 0) + 1
    return [v for v, p in zip(variants, picked) if p]


class Report:
    """OUT/report.json checked: its arrays, its axes, and every image it
    names (checked here, so that a bad path fails before any
    figure is drawn)."""

    def __init__(self, out):
        self.out = out
        self.src = src = os.path.join(out, 'report.json')
        self.doc = doc = load_json(src, 'penumbra-report')
        for key in ('axes', 'renderers', 'variants', 'comparisons',
                    'missing', 'failures', 'plots'):
            if not isinstance(doc.get(key, []), list):
                raise BadInput(src, f'"{key}" must be an array')
        for i, a in enumerate(doc.get('axes', [])):
            if not isinstance(obj(a).get('values'), list):
                raise BadInput(src, f'axes[{i}]: expected {{"values": [...]}}')
        self.study = obj(doc.get('study'))
        self.renderers = objs(doc.get('renderers'))
        self.ranking = obj(doc.get('ranking'))
        self.variants = objs(doc.get('variants'))
        self.comps = objs(doc.get('comparisons'))
        self.shown = shown_variants(self.variants)
        shown_ids = {id(v) for v in self.shown}
        self.uris = {}
        for v in self.variants:
            for r in objs(v.get('renders')):
                for key in ('image', 'difference', 'flip_map'):
                    ctx = f'variant {v.get("id")}: {key}'
                    if r.get(key) is not None:
                        path = inside(out, r[key], src, ctx)
                        if id(v) in shown_ids:
                            self.uris[r[key]] = data_uri(path, src, ctx)
        lp = doc.get('lowpoly')
        self.lowpoly = None if lp is None else LowPoly(lp, out, src)
        self.filtering = filtering_entries(doc.get('filtering'), out, src)
        ip = doc.get('interplay')
        if ip is not None and not (isinstance(ip, dict) and
                                   isinstance(ip.get('rows'), list)):
            raise BadInput(src, '"interplay" must be null or an object with '
                           '"rows"')
        self.interplay = ip
        self.units = obj(doc.get('units'))
        self.terminator = region(self.units.get('terminator_region_deg'),
                                 [60.0, 100.0])
        self.lit = region(self.units.get('lit_region_deg'), [0.0, 60.0])

    def ranking_groups(self):
        """[(title, ranking entries)]: overall, then per scene."""
        rk = self.ranking
        return [('overall', objs(rk.get('overall')))] + [
            (f'scene {s.get("scene")}', objs(s.get('methods')))
            for s in objs(rk.get('per_scene'))]


def filtering_entries(entries, out, src):
    """report['filtering'] checked: [] for null, else each entry with its
    filtering.json loaded into entry['doc'] and its path in entry['path']."""
    if entries is None:
        return []
    if not isinstance(entries, list):
        raise BadInput(src, '"filtering" must be an array or null')
    checked = []
    for i, e in enumerate(entries):
        e = obj(e)
        ctx = f'filtering[{i}]'
        for key in ('map', 'run'):
            if not isinstance(e.get(key), str):
                raise BadInput(src, f'{ctx}: expected a string "{key}"')
        path = inside(out, e.get('json'), src, f'{ctx}: json')
        checked.append(dict(e, path=path,
                            doc=load_json(path, 'penumbra-filtering')))
    return checked


class LowPoly:
    """report['lowpoly'] checked, with every variant and comparison placed in
    a group (the scene and the values of the non-convergence axes) at a
    level (the convergence axis' value)."""

    def __init__(self, lp, out, src):
        if not isinstance(lp, dict):
            raise BadInput(src, '"lowpoly" must be an object or null')
        for key in ('axes', 'renderers', 'variants', 'comparisons',
                    'missing'):
            if not isinstance(lp.get(key, []), list):
                raise BadInput(src, f'lowpoly: "{key}" must be an array')
        self.axes = objs(lp.get('axes'))
        for i, a in enumerate(self.axes):
            if not isinstance(a.get('values'), list):
                raise BadInput(src, f'lowpoly: axes[{i}]: expected '
                               '{"values": [...]}')
        ptr = lp.get('convergence_axis')
        self.conv = next((i for i, a in enumerate(self.axes)
                          if ptr is not None and a.get('pointer') == ptr),
                         0 if len(self.axes) == 1 else None)  # the only one
        self.variants = objs(lp.get('variants'))
        self.comps = objs(lp.get('comparisons'))
        self.renderers = objs(lp.get('renderers'))
        self.missing = list({json.dumps(m, sort_keys=True): m for m in objs(
            lp.get('missing'))}.values())  # once per variant: once here
        self.ranking = obj(lp.get('ranking'))
        self.units = obj(lp.get('units'))
        for v in self.variants:  # every image path, before any drawing
            for r in objs(v.get('renders')):
                for key in ('image', 'difference', 'flip_map'):
                    if r.get(key) is not None:
                        inside(out, r[key], src,
                               f'lowpoly variant {v.get("id")}: {key}')
        self._levels()
        self.groups = list(dict.fromkeys(
            self.place(x)[0] for x in self.variants + self.comps))
        self.rend_ids = list(dict.fromkeys(
            [str(r.get('id')) for r in self.renderers] +
            [str(c.get('renderer')) for c in self.comps]))
        self.offsets = list(dict.fromkeys(
            [str(o) for r in self.renderers for o in r.get('offsets') or []] +
            [str(c.get('offset')) for c in self.comps]))

    def _levels(self):
        """The x axis of the convergence figures and the shadow tables."""
        if self.conv is not None:
            vals = self.axes[self.conv]['values']
            self.numeric = bool(vals) and all(
                math.isfinite(num(t)) for t in vals)
            self.levels = sorted(vals, key=num) if self.numeric else \
                list(vals)
            self.xlabel = str(self.axes[self.conv].get(
                'label', self.axes[self.conv].get('pointer')))
        else:  # no convergence axis: the variants' axis values as text
            self.numeric = False
            self.levels = list(dict.fromkeys(
                self.place(v)[1] for v in self.variants + self.comps))
            self.xlabel = 'variant'

    def place(self, x):
        """(group, level) of a variant or comparison; level None when its
        axis values do not fit the axes."""
        av, scene = x.get('axis_values'), str(x.get('scene'))
        if not isinstance(av, list) or len(av) != len(self.axes):
            return scene, None
        if self.conv is None:
            return scene, ', '.join(axis_text(v, i)
                                    for i, v in enumerate(av)) or '—'
        return scene + ''.join(
            f', {a.get("label", a.get("pointer"))}={axis_text(v, i)}'
            for i, (a, v) in enumerate(zip(self.axes, av))
            if i != self.conv), av[self.conv]

    def level_index(self, x):
        level = self.place(x)[1]
        if self.conv is None:
            return self.levels.index(level) if level in self.levels else None
        return None if level is None else axis_index(self.levels, level)

    def level_text(self, level):
        return axis_text(level, 0) if self.conv is not None else str(level)

    def log2_levels(self):
        """Whether the convergence figures use a log2 x axis."""
        return self.numeric and len(self.levels) >= 2 and all(
            num(t) > 0 for t in self.levels)

    def series(self, group, own):
        """{(renderer, offset): {metric: array over levels}} of the group's
        comparisons: own=False the evaluator against evaluator:analytic,
        own=True the other renderers against their own analytic render."""
        acc = {}
        for c in self.comps:
            rend = str(c.get('renderer'))
            if (rend != REF) != own or \
                    c.get('reference') != f'{rend}:{LP_TRUTH}' or \
                    self.place(c)[0] != group:
                continue
            j = self.level_index(c)
            if j is None:
                continue
            s = acc.setdefault((rend, str(c.get('offset'))), {})
            for metric, *_ in LP_PANELS + LP_SIDE:
                a = s.setdefault(metric, np.zeros((2, len(self.levels))))
                v = get_metric(c, metric)
                if math.isfinite(v):
                    a[:, j] += (v, 1)
        order = {o: i for i, o in enumerate(self.offsets)}
        rorder = {r: i for i, r in enumerate(self.rend_ids)}
        out = {}
        for key in sorted(acc, key=lambda k: (rorder.get(k[0], 0),
                                              order.get(k[1], 0))):
            with np.errstate(invalid='ignore', divide='ignore'):
                out[key] = {m: a[0] / a[1] for m, a in acc[key].items()}
        return out

    def cast_shadow_pixels(self, group):
        """The reference cast-shadow pixel counts of a group's
        comparisons (empty when the scene casts no shadow)."""
        return sorted({int(get_metric(c, 'shadow.shadowed_pixels'))
                       for c in self.comps if self.place(c)[0] == group and
                       get_metric(c, 'shadow.shadowed_pixels') > 0})
