"""The bump methods' ranking statistics of report.json, as the figures,
tables and page read them (issue 37's contract: /statistics primary_metric,
rule, overall, per_scene, by_axis, headline, notes), with fall-backs for a
report.json written before those fields existed.

One reading of the rank groups serves every table, figure and page section:
ranked() (the rule itself is the C++ side's: statistics.rule says it; a
group is dense-numbered 1, 2, ... from each entry's `rank`). Where a field is
absent:
  - rank groups: the old `rank` (tied methods share one), dense-numbered;
    the group's leader: its first method by the primary metric;
  - statistics.headline: the overall ranking's first sentence;
  - by_axis: computed here from the comparisons (evaluator against its
    displacement truth, the ranking's rows): per level, each method's mean
    over the level's variants with a 95 % percentile bootstrap interval
    (2000 resamples, fixed seed), and no rank groups (none are invented).
Nothing here draws or writes.
"""
import math

import numpy as np

from penumbra_data import (
    COMBINED_UNIT, METRICS, PRIMARY, REF, axis_index, axis_labels, fmt, num,
    obj, objs)

MEAN_METRICS = (PRIMARY, 'profile.rmse_terminator', 'view.rmse_grazing',
                'profile.position_error_deg', 'image.rmse', 'image.ssim',
                'image.flip')
BOOTSTRAP = 2000
# The handful of methods a profile, line or grid figure shows by default
# (raw bump included): more lines than this in one panel no longer read.
HANDFUL = 5


def strings(xs):
    return [str(x) for x in xs] if isinstance(xs, list) else []


def pair(ci):
    """(lo, hi) of a JSON interval; nan where undefined."""
    ok = isinstance(ci, list) and len(ci) == 2
    return (num(ci[0]), num(ci[1])) if ok else (math.nan, math.nan)


def mean_of(entry, metric):
    """(mean, lo, hi) of a MethodStats entry's metric: for the primary
    metric the entry's own combined value and interval (at the ranking's
    confidence, the one the rank groups and the headline use), else its
    `means` entry (95 %)."""
    if metric == PRIMARY and math.isfinite(num(entry.get(PRIMARY))):
        return (num(entry.get(PRIMARY)),) + pair(entry.get('combined_ci'))
    m = obj(obj(entry.get('means')).get(metric))
    if m:
        return (num(m.get('mean')),) + pair(m.get('ci'))
    return (math.nan,) * 3


def ranked(rs):
    """THE reading of a RankingStats' rank groups: its methods as rows
    {'method', 'group' (1, 2, ... dense; None without a rank), 'leader',
    'value', 'ci', 'versus', 'entry'}, ordered by group, then by the
    primary metric (undefined last). Every table, figure and page section
    that shows rank groups calls this."""
    entries = objs(obj(rs).get('methods'))
    ranks = sorted({e['rank'] for e in entries if type(e.get('rank')) is int})
    dense = {r: i + 1 for i, r in enumerate(ranks)}
    rows = []
    for e in entries:
        value = num(e.get(PRIMARY))
        rows.append({'method': str(e.get('method')), 'entry': e,
                     'group': dense.get(e.get('rank')), 'value': value,
                     'ci': pair(e.get('combined_ci')),
                     'versus': obj(e.get('versus_leader'))})
    rows.sort(key=lambda r: (r['group'] is None, r['group'] or 0,
                             not math.isfinite(r['value']),
                             r['value'] if math.isfinite(r['value']) else 0))
    names = {r['method'] for r in rows}
    for r in rows:
        lead = r['entry'].get('group_leader')
        first = next(x['method'] for x in rows if x['group'] == r['group'])
        r['leader'] = str(lead) if lead in names else first
    return rows


def primary_metric(st):
    """{'id', 'name', 'unit'} of the ranking metric."""
    p = {'id': PRIMARY, 'name': 'combined error relative to raw bump',
         'unit': COMBINED_UNIT + ' (1 = raw bump, lower is better)'}
    p.update({k: v for k, v in obj(st.get('primary_metric')).items()
              if k in p and isinstance(v, str)})
    return p


def unquoted(t):
    """A label without the JSON quotes older report.json files put around
    a named axis' string values."""
    return t[1:-1] if len(t) >= 2 and t[0] == t[-1] == '"' else t


def short_ids(axis):
    """Short labels of an axis' values for ticks and file names: its
    value_ids, else numbers as %g, light directions as 'az A°, el E°',
    other short labels as they are, long ones as '#1', '#2' (a caption
    keys them: numbered_key)."""
    vals = axis.get('values') if isinstance(axis.get('values'), list) else []
    ids = axis.get('value_ids')
    if isinstance(ids, list) and len(ids) == len(vals) and all(
            isinstance(t, str) for t in ids):
        return list(ids)
    out = []
    for i, t in enumerate(axis_labels(axis)):
        t = unquoted(t).replace('azimuth ', 'az ').replace('elevation ', 'el ')
        out.append(t if len(t) <= 16 else f'#{i + 1}')
    return out


def numbered_key(levels):
    """'#2: long label; #3: ...' of the levels short_ids numbered."""
    return '; '.join(f'{lv["id"]}: {lv["label"]}' for lv in levels
                     if lv['id'].startswith('#'))


class Stats:
    """report.json's statistics, read once (report: penumbra_data.Report
    or anything with .doc, .variants and .comps)."""

    def __init__(self, report):
        self.report = report
        st = obj(report.doc.get('statistics'))
        self.present = isinstance(st.get('overall'), dict)
        self.primary = primary_metric(st)
        self.overall = obj(st.get('overall'))
        self.rows = ranked(self.overall)
        self.methods = [r['method'] for r in self.rows]
        self.scenes = [(str(s.get('scene')), s)
                       for s in objs(st.get('per_scene'))]
        rule = str(st.get('rule') or (
            'as this report.json ranks them: ' +
            str(st.get('test', 'methods tied by the tests share a rank'))))
        # One sentence that names itself: "Rank groups: ..." (the C++
        # side's rule may already begin so).
        rule = rule.rstrip().rstrip('.') + '.'
        self.rule = rule if rule.lower().startswith('rank groups') else \
            'Rank groups: ' + rule
        self.headline = strings(st.get('headline')) or strings(
            self.overall.get('headline'))[:1]
        self.notes = strings(st.get('notes'))
        self.confidence = num(self.overall.get('confidence',
                                               st.get('confidence')))
        self._by_axis = [axis_entry(a) for a in objs(st.get('by_axis'))]
        self.computed_axes = not self._by_axis
        self._computed = None

    def by_axis(self):
        """[axis entry]: report.json's by_axis, else computed from the
        comparisons (once, on first use)."""
        if self._by_axis:
            return self._by_axis
        if self._computed is None:
            self._computed = computed_axes(self.report)
        return self._computed

    def axis(self, pointer):
        """The by_axis entry of an axis pointer (or name), or None."""
        return next((a for a in self.by_axis() if a['pointer'] == pointer),
                    None)

    def interval_text(self, metric=PRIMARY, confidence=None):
        """What a metric's intervals are, for captions: the primary
        metric's at the ranking's confidence (`confidence`, default the
        overall ranking's), any other's 95 %."""
        c = self.confidence if confidence is None else num(confidence)
        if metric != PRIMARY or not math.isfinite(c) or c < 0.99:
            return '95 % bootstrap interval over variants'
        return ('simultaneous 95 % intervals over variants (each at '
                f'{fmt(c * 100, digits=4)} %, Bonferroni over the methods)')


def axis_entry(a):
    """A by_axis entry of report.json, normalised."""
    levels = [{'value': lv.get('value'),
               'label': unquoted(str(lv.get('value_label', lv.get('value')))),
               'id': str(lv.get('value_id', lv.get('value_label', ''))),
               'ranking': obj(lv.get('ranking'))}
              for lv in objs(a.get('levels'))]
    return {'pointer': str(a.get('pointer')),
            'label': str(a.get('label', a.get('pointer'))),
            'numeric': a.get('numeric') is True and all(
                math.isfinite(num(lv['value'])) for lv in levels),
            'levels': levels, 'interactions': objs(a.get('interactions')),
            'computed': False}


def variant_values(report):
    """{metric: {method: {variant id: value}}} over the ranking's rows
    (evaluator against its displacement truth), the primary metric C
    included: (E_term + E_view) / (E_term(none) + E_view(none)) per
    variant."""
    table = {m: {} for m in MEAN_METRICS}
    for c in report.comps:
        if c.get('renderer') != REF or \
                c.get('reference') != f'{REF}:displacement':
            continue
        for metric in MEAN_METRICS[1:]:
            section, _, key = metric.partition('.')
            table[metric].setdefault(str(c.get('method')), {})[
                c.get('variant')] = num(obj(c.get(section)).get(key))
    term, view = table['profile.rmse_terminator'], table['view.rmse_grazing']
    base = {v: term.get('none', {}).get(v, math.nan) +
            view.get('none', {}).get(v, math.nan)
            for v in term.get('none', {})}
    for m in term:
        table[PRIMARY][m] = {
            v: (t + view.get(m, {}).get(v, math.nan)) / base[v]
            for v, t in term[m].items() if base.get(v, 0) > 0}
    return table


def bootstrap(values, rng):
    """(mean, lo, hi): the 95 % percentile bootstrap of the mean."""
    x = np.asarray([v for v in values if math.isfinite(v)], dtype=float)
    if x.size == 0:
        return (math.nan,) * 3
    means = x[rng.integers(0, x.size, (BOOTSTRAP, x.size))].mean(axis=1)
    lo, hi = np.percentile(means, [2.5, 97.5])
    return float(x.mean()), float(lo), float(hi)


def computed_axes(report):
    """by_axis entries computed from the comparisons (a report.json without
    statistics.by_axis): per axis and level, every method's means with
    their intervals, ordered by the primary metric, without rank groups."""
    table = variant_values(report)
    out = []
    for k, axis in enumerate(objs(report.doc.get('axes'))):
        vals = axis.get('values') if isinstance(axis.get('values'), list) \
            else []
        numeric = bool(vals) and all(math.isfinite(num(v)) for v in vals)
        order = sorted(range(len(vals)), key=lambda i: num(vals[i])) \
            if numeric else range(len(vals))
        labels = [unquoted(t) for t in axis_labels(axis)]
        ids = short_ids(axis)
        levels = []
        for i in order:
            at = {v.get('id') for v in report.variants
                  if isinstance(v.get('axis_values'), list) and
                  len(v['axis_values']) > k and
                  axis_index([vals[i]], v['axis_values'][k]) == 0}
            levels.append({'value': vals[i], 'label': labels[i], 'id': ids[i],
                           'ranking': level_ranking(table, at)})
        out.append({'pointer': str(axis.get('pointer')),
                    'label': str(axis.get('label', axis.get('pointer'))),
                    'numeric': numeric, 'levels': levels,
                    'interactions': [], 'computed': True})
    return out


def level_ranking(table, variants):
    """A RankingStats-like {'methods': [...]} over the given variants:
    means of every MEAN_METRICS entry with bootstrap intervals (a fixed
    seed per level: the same bytes every run), ordered by the primary
    metric; no `rank` (the rule needs the paired tests of the C++ side)."""
    rng = np.random.default_rng(1)
    methods = []
    for m in table[PRIMARY]:
        means = {}
        for metric in MEAN_METRICS:
            vals = [table[metric].get(m, {}).get(v, math.nan)
                    for v in sorted(variants, key=str)]
            mean, lo, hi = bootstrap(vals, rng)
            means[metric] = {'mean': mean, 'ci': [lo, hi]}
        c = means[PRIMARY]
        methods.append({'method': m, PRIMARY: c['mean'],
                        'combined_ci': c['ci'], 'means': means})
    methods.sort(key=lambda e: (not math.isfinite(e[PRIMARY]),
                                num(e[PRIMARY])))
    return {'variants': len(variants), 'methods': methods}


def level_confidence(axis):
    """The confidence of an axis' level rankings (the first that says)."""
    return next((lv['ranking']['confidence'] for lv in axis['levels']
                 if 'confidence' in lv['ranking']), None)


def depends(axis):
    """{method: interaction} of the methods whose effect depends on the
    axis' level."""
    return {str(i.get('method')): i for i in axis['interactions']
            if i.get('depends') is True}


def flips(axis):
    """{method: interaction} of the methods whose effect depends on the
    axis' level and that help at one level and hurt at another (the
    finding a paper needs), most significant first."""
    out = [i for i in depends(axis).values()
           if {'helps', 'hurts'} <= {lv.get('verdict')
                                     for lv in objs(i.get('levels'))}]
    out.sort(key=lambda i: (num(i.get('p_holm')), str(i.get('method'))))
    return {str(i.get('method')): i for i in out}


FLIPS_SHOWN = 2


def line_methods(shown, axis):
    """A line figure's default methods: the highlighted ones and up to
    FLIPS_SHOWN more that help at one level of this axis and hurt at
    another."""
    return list(shown) + [m for m in flips(axis) if m not in shown][
        :FLIPS_SHOWN]


def level_leaders(stats):
    """The leaders of the best rank group in each level of each axis, in
    axis and level order (the methods that win somewhere); without rank
    groups (computed by_axis), each level's lowest mean."""
    out = []
    for axis in stats.by_axis():
        for lv in axis['levels']:
            rows = ranked(lv['ranking'])
            if rows:
                out.append(rows[0]['leader'])
    return out


def highlighted(stats, available, named=()):
    """The methods a profile, line or grid figure shows by default, in this
    order: `none` (the baseline), the methods named (the study's
    figures.methods, or the command line's), the leader of the best rank
    group overall, the leaders of the best rank group in each level of
    each axis (so a method that wins only at one amplitude is shown), then
    the next best overall by the primary metric; at most HANDFUL in all
    unless more are named. Only methods in `available` are kept."""
    auto = ['none'] + [r['leader'] for r in stats.rows if r['group'] == 1][:1]
    auto += level_leaders(stats) + stats.methods
    picks = [m for m in dict.fromkeys(['none'] + list(named))
             if m in available]
    for m in auto + list(available):
        if len(picks) >= HANDFUL:
            break
        if m in available and m not in picks:
            picks.append(m)
    return picks


def metric_unit(metric):
    """The unit of a metric as figures and tables state it (the CSV
    column's)."""
    return METRICS.get(metric, (metric, ''))[1]
