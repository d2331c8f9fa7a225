"""report.html's "What is achievable" section (templates/achievable.html.j2)
from the study's fit/fit.json (penumbra_achievable.load_fit), or, without
one, the line that says how to get it.

Errors are terminator-profile RMSE pooled over variants, shown in % of
albedo·E/π with their 95 % intervals; shares and constants as fractions.
The fitted table's error is always the held-out one (fitted without the
family it is measured on); the study floor on the family, which was
fitted with it, appears only beside it and labelled in-sample.
"""
import math

from penumbra_achievable import inputs_text, more_inputs, share_caption
from penumbra_context import ci_cell, figure_file, table
from penumbra_data import fmt

PCT = '% of albedo·E/π'


def pct_cell(iv):
    """'6.49 [4.50, 8.39]' of a [value, low, high] fraction, in %, as a
    right-aligned table cell."""
    return ci_cell(iv[0], iv[1:], 100.0, digits=2)


def pct(iv):
    return pct_cell(iv)['text']


def pct_value(v):
    """One fraction without an interval, in % (n/a when undefined), as a
    right-aligned table cell."""
    return {'text': f'{v * 100:.2f}', 'cls': 'n'} if math.isfinite(v) \
        else {'text': 'n/a', 'cls': 'n na'}


def frac_cell(iv, digits=2):
    return ci_cell(iv[0], iv[1:], 1.0, digits=digits)


def frac(iv, digits=2):
    return frac_cell(iv, digits)['text']


def absent_context(fit_file):
    return {'absent': f'No {fit_file} in this study folder: `penumbra fit '
            'STUDY` then `penumbra report STUDY` add the "What is '
            'achievable" section (the lowest error any light,deviation '
            'factor reaches, each method\'s share of it, and a table fitted '
            'and held out by scene family).'}


def verdict(paired, first, second):
    """The project's tie rule on a paired difference (first - second, both
    pooled over the same resamples): a tie when its 95 % interval holds 0,
    else the lower one is named."""
    if paired is None:
        return 'n/a'
    if paired['tie']:
        return 'tie'
    return f'{first} lower' if paired['difference'][0] < 0 else f'{second} lower'


def held_out_cell(iv):
    """A held-out error, or why there is none (one family)."""
    return (pct_cell(iv) if iv is not None
            else {'text': 'none: one family', 'cls': 'n na'})


def difference_cell(paired):
    """A paired difference in percentage points, with its interval."""
    return pct_cell(paired['difference']) if paired else pct_value(math.nan)


def comparison_sentence(fit):
    """Whether the held-out table beats the best shipped method out of
    sample, pooled over the study, by their paired difference; None without
    a shipped method or without held-out families."""
    paired, name = fit['held_out_minus_best'], fit['best_method']
    if paired is None or name is None:
        return None
    best = next(m for m in fit['methods'] if m['method'] == name)
    h, d = fit['held_out_pooled'], paired['difference']
    head = (f'Out of sample, the fitted table held out by scene family '
            f'has E = {pct(h)} {PCT} over {fit["variants"]} variants; the '
            f'best shipped method, {name}, has E = {pct(best["error"])} '
            f'{PCT}. Paired over the same resamples, held-out minus {name} '
            f'is {pct(d)} percentage points: ')
    if paired['tie']:
        text = f'the interval holds 0, so the held-out table and {name} are tied.'
    else:
        lower = 'the held-out table' if d[0] < 0 else name
        text = f'the interval excludes 0, and {lower} is lower.'
    return head + text + ' ' + family_tally(fit)


def family_tally(fit):
    """'Per held-out family, against the best shipped method there: tie
    in 3, fitted table lower in 1 (of 4).'"""
    counts = {}
    for f in fit['held_out']:
        v = verdict(f['held_out_minus_best'], 'fitted table',
                    'best shipped method')
        counts[v] = counts.get(v, 0) + 1
    return ('Per held-out family, against the best shipped method there: ' +
            ', '.join(f'{v} in {n}' for v, n in sorted(counts.items())) +
            f' (of {len(fit["held_out"])}).')


def held_out_table(fit):
    head = ['held-out family', 'variants',
            f'fitted table, held out: E ({PCT})',
            'best shipped method there',
            f'its E ({PCT})', f'raw bump E ({PCT})',
            'held-out − best, paired (percentage points)', 'held-out vs best',
            f'in-sample (the study floor, fitted with the family): E '
            f'({PCT}; not an out-of-sample error)']
    rows = [[h['family'], h['variants'], pct_cell(h['held_out']),
             h['best_method'], pct_cell(h['best']), pct_cell(h['none']),
             difference_cell(h['held_out_minus_best']),
             verdict(h['held_out_minus_best'], 'fitted table',
                     h['best_method']),
             pct_value(h['in_sample'])]
            for h in fit['held_out']]
    return table(head, rows)


def symbol(c):
    """A constant's symbol: the first word of its description ('k in
    alpha^2 = k tan^2(delta)')."""
    return c['constant'].split(' ', 1)[0]


def inside(c):
    lo, hi = c['fitted'][1:]
    return math.isfinite(lo + hi) and lo <= c['published'] <= hi


def reference_text(c, noun=''):
    """What a constant is fitted against: the published value, or (a
    constant no paper publishes, shading-offset's s) the study's own."""
    return ('the published' + noun if c['reference'] == 'published'
            else c['reference'])


def constant_sentence(group):
    """One sentence for a method's constants: fitted values with their
    intervals against the published ones, and whether those lie inside.
    A method with several constants fits them together."""
    bound = group[0]['at_bound']
    edge = (f' The fit reached the edge of its range ({bound}): E would '
            'fall further beyond it, and the intervals hold within it.'
            if bound else '')
    if len(group) == 1:
        c = group[0]
        ref = reference_text(c)
        return (f'{c["method"]}: fitted {c["constant"]}: {symbol(c)} = '
                f'{frac(c["fitted"], 3)} (dimensionless; 95 % bootstrap '
                f'interval over variants) against {ref} '
                f'{fmt(c["published"], digits=4)}; '
                f'{reference_text(c, " constant")} '
                'lies ' + ('inside' if inside(c) else 'outside') +
                ' the interval.' + edge)
    names = [symbol(c) for c in group]
    where = [n for n, c in zip(names, group) if inside(c)]
    if len(where) == len(group):
        verdict = 'every published constant lies inside its interval'
    elif not where:
        verdict = 'no published constant lies inside its interval'
    else:
        verdict = ('the published ' + ' and '.join(where) + ' lie'
                   + ('s' if len(where) == 1 else '') + ' inside '
                   + ('its interval' if len(where) == 1 else 'their intervals')
                   + ', the published '
                   + ' and '.join(n for n in names if n not in where)
                   + ' outside')
    form = group[0]['constant'].split(' in ', 1)[-1]
    return (f'{group[0]["method"]}: fitted together in {form}: '
            + ', '.join(f'{symbol(c)} = {frac(c["fitted"], 4)}'
                        for c in group)
            + ' (dimensionless; 95 % bootstrap intervals over variants) '
            'against the published '
            + ', '.join(f'{symbol(c)} = {fmt(c["published"], digits=4)}'
                        for c in group)
            + f'; {verdict}.' + edge)


def constants_context(fit):
    """A sentence per method with fitted constants: fitted values with their
    intervals, the published ones, whether they lie inside; and a table of
    the errors (a method's constants share them: they are fitted
    together)."""
    groups = {}
    for c in fit['constants']:
        groups.setdefault(c['method'], []).append(c)
    sentences = [constant_sentence(g) for g in groups.values()]
    rows = []
    for group in groups.values():
        for c in group:
            digits = 3 if len(group) == 1 else 4
            rows.append([c['method'] + ('' if len(group) == 1
                                        else f' {symbol(c)}'),
                         {'text': fmt(c['published'], digits=5)
                          + ('' if c['reference'] == 'published'
                             else f' ({c["reference"]})'),
                          'cls': 'n'},
                         frac_cell(c['fitted'], digits),
                         'yes' if inside(c) else 'no',
                         pct_cell(c['error_published']),
                         held_out_cell(c['error_held_out']),
                         difference_cell(c['held_out_minus_published']),
                         verdict(c['held_out_minus_published'],
                                 'fitted', 'published'),
                         pct_cell(c['error_in_sample'])])
    head = ['method', 'published (dimensionless)',
            'fitted [95 % interval] (dimensionless)',
            'published inside', f'E at published ({PCT})',
            f'E fitted, held out by family ({PCT})',
            'held out − published, paired (percentage points)',
            'held out vs published',
            f'E fitted, in-sample ({PCT}; fitted on these variants)']
    probed = [c for c in fit['constants']
              if c['probe_minus_rendered'] is not None]
    return {'sentences': sentences,
            'table': table(head, rows) if rows else None,
            'probed': ', '.join(c['method'] for c in probed),
            'probe_check': (fmt(max(c['probe_minus_rendered']
                                    for c in probed) * 100, digits=2)
                            if probed else None)}


def offset_held_out_text(o, ref):
    """E with the parameter chosen without each scene against the
    reference's, paired; or, with a single low-poly scene, that there is
    nothing to hold out."""
    held = o['held_out_minus_published']
    if held is None:
        return (f'E = {pct(o["error_published"])} {PCT} at {ref}; no '
                'held-out error: the variants are of one scene, and a value '
                'chosen without it has nothing to be chosen on.')
    return (f'Chosen without each scene, E = {pct(o["error_held_out"])} '
            f'{PCT} against {pct(o["error_published"])} at {ref}: '
            f'{pct(held["difference"])} percentage points, paired, '
            + ('a tie.' if held['tie'] else
               ('the refitted value lower.' if held['difference'][0] < 0
                else f'{ref} lower.')))


def offsets_context(fit):
    """The low-poly offsets' parameters refitted among their rendered
    values: a sentence each, and a table of E at every value; None where
    the fit refitted none (a study without a parameter rendered at two or
    more values, or a fit.json from before them)."""
    offsets = fit['offset_parameters']
    if not offsets:
        return None
    sentences, rows = [], []
    for o in offsets:
        ref = reference_text(o)
        edge = (f' It is the end of the rendered values ({o["at_bound"]}): '
                'E may fall further beyond them.' if o['at_bound'] else '')
        sentences.append(
            f'{o["method"]}: {o["constant"]} refitted among '
            f'{len(o["values"])} rendered values, over {o["variants"]} '
            f'low-poly variants: {symbol(o)} = {frac(o["fitted"], 3)} '
            f'(95 % bootstrap interval over variants) against {ref} '
            f'{fmt(o["published"], digits=4)}. '
            + offset_held_out_text(o, ref) + edge)
        for v in o['values']:
            marks = [m for m, hit in (('fitted', v['value'] == o['fitted'][0]),
                                      (ref, v['value'] == o['published']))
                     if hit]
            rows.append([o['method'], {'text': fmt(v['value'], digits=4),
                                       'cls': 'n'},
                         pct_cell(v['error']), ', '.join(marks)])
    return {'sentences': sentences,
            'table': table(['offset', 'parameter value (its unit: see '
                            'above)', f'image E ({PCT})', ''], rows)}


def sees_more(fit, method):
    """Whether a method sees an input the floor's grid does not, so that
    the floor does not bound it."""
    return method in more_inputs(fit)


def nested_sentences(fit):
    """Per floor of fewer inputs on the same grid: what the fit's added
    inputs lower the floor by, paired, and that this is in-sample."""
    out = []
    for n in fit['nested']:
        d = n['gain']['difference']
        gain = [-d[0], -d[2], -d[1]]
        out.append(
            f'On the same grid, a factor of the {inputs_text(n["inputs"])} '
            f'alone reaches E* = {pct(n["floor"])} {PCT}; the added inputs '
            f'lower the floor by {pct(gain)} percentage points (paired over '
            'the same resamples' + ('; a tie' if n['gain']['tie'] else '') +
            '). Both floors are in-sample, and a grid with more inputs has '
            'more cells to fit: the held-out table below is the test of '
            'whether the inputs help on scenes the fit never saw.')
    return out


def image_context(fit):
    """The image RMSE's per-variant floors: a sentence and every method's
    row; None for a fit.json written before them."""
    im = fit['image']
    if im is None:
        return None
    rows = [[m['method'] + (' †' if sees_more(fit, m['method']) else ''),
             pct_cell(m['error']), frac_cell(m['share'])]
            for m in im['methods']]
    best = next((m for m in im['methods'] if not m['method'].startswith(
        'fitted') and math.isfinite(m['error'][0])), None)
    sentence = (
        f'Image RMSE over the pixels fully covered in both: raw bump '
        f'{pct(im["none"])} {PCT}; a factor of the '
        f'{inputs_text(fit["inputs"])} fitted to each variant alone reaches '
        f'{pct(im["floor"])}. That floor is in-sample by design: what lies '
        'above it no factor of these inputs can remove on that image, '
        'whatever its constants.')
    if best is not None:
        tied = [m['method'] for m in im['methods']
                if m['group'] is not None and m['group'] == best['group']
                and m['method'] != best['method']]
        sentence += (
            f' The lowest shipped method, {best["method"]}, reaches '
            f'{pct(best["error"])}: {frac(best["share"])} of the floors\' '
            'gain on raw bump, ' +
            ('tied by share (paired over the same resamples) with ' +
             ', '.join(tied) if tied else
             'above every other method\'s share (paired over the same '
             'resamples, no interval holds 0)') + '.')
    return {'sentence': sentence,
            'table': table(['method', f'image E ({PCT})',
                            'share of the floors\' gain (fraction)'], rows)}


def achievable_context(fit, figs, fit_file):
    """The section's context; fit None: the line saying how to get it."""
    if fit is None:
        return absent_context(fit_file)
    f = fit['floor']
    families = table(
        ['scene family', 'variants', f'floor E* ({PCT})',
         f'raw bump E ({PCT})'],
        [[e['scope'], e['variants'], pct_cell(e['floor']),
          pct_cell(e['none'])]
         for e in fit['families']])
    shares = table(
        ['method', f'E ({PCT})', 'share of the achievable improvement '
         '(fraction)'],
        [[m['method'] + (' †' if sees_more(fit, m['method']) else ''),
          pct_cell(m['error']), frac_cell(m['share'])]
         for m in fit['methods']])
    return {'absent': None, 'file': fit_file, 'unit': fit['unit'],
            'inputs': inputs_text(fit['inputs']),
            'nested': nested_sentences(fit),
            'dagger': any(sees_more(fit, m['method']) for m in fit['methods']),
            'floor': pct(f['floor']), 'none': pct(f['none']),
            'variants': f['variants'], 'pct': PCT,
            'unconverged': fit['unconverged_truths'],
            'families': families, 'shares': shares,
            'share_figure': figure_file(
                figs['share'], 'share of the achievable improvement',
                'figures/achievable-share.{png,svg,pdf}: ' +
                share_caption(fit)) if figs.get('share') else None,
            'contour_figure': figure_file(
                figs['contour'], 'G* and the methods over light angle and '
                'deviation', 'figures/achievable-contour.{png,svg,pdf}: '
                'top, G (fraction of the light let through) of the study '
                'floor G* and of each method over the light angle from Ng '
                'and the shading-normal deviation (degrees; chiang2019 and '
                'estevez2019 with Ns tilted towards the light); bottom, '
                'each one\'s difference from G* (blue: lets more light '
                'through than the floor, red: less). Blank: cells no '
                'variant lights.')
            if figs.get('contour') else None,
            'held_out': held_out_table(fit) if fit['held_out'] else None,
            'comparison': comparison_sentence(fit),
            'constants': constants_context(fit),
            'offsets': offsets_context(fit),
            'image': image_context(fit)}
