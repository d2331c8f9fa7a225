#!/usr/bin/python3
"""report.html's "What is achievable" section and the achievable-share and
achievable-contour figures (issue 39), from a synthetic study folder
(report_fixture.py) and a synthetic fit/fit.json (fit_fixture.py), without
the C++ binary.

Usage: test_report_achievable.py SOURCE_DIR [unittest options]

Checks that
  - the section appears iff STUDY/fit/fit.json exists, and without it the
    page says in one line how to get it;
  - the numbers on the page are fit.json's, formatted (% of albedo·E/π
    with intervals, shares, k and deshmukh2020's d0, d1 as fractions, with
    whether each published constant lies inside its interval);
  - the image RMSE's per-variant floors and each method's share of them
    are fit.json's image_floor, and a fit.json without one says so;
  - the fitted table's column is the held-out error, the in-sample one only
    in its labelled column;
  - the tie sentence and the per-family verdicts follow the interval rule:
    overlapping intervals say tie, disjoint ones name the lower;
  - `report.py figure --kind achievable-share|achievable-contour` writes
    the same bytes twice, a paper PDF 3.5 or 7 in wide;
  - a bad fit.json (missing key, wrong shape, malformed) is one line
    'report.py: <fit.json>: <JSON pointer>: ...', exit 2, nothing written.
"""
import copy
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), '..', '..')
REPORT = os.path.join(SOURCE, 'harness', 'report.py')
sys.path[:0] = [os.path.dirname(os.path.abspath(__file__)),
                os.path.join(SOURCE, 'harness')]
sys.dont_write_bytecode = True

import fit_fixture as ff  # noqa: E402
import report_fixture as fx  # noqa: E402
from penumbra_achievable import load_fit, share_groups  # noqa: E402
from penumbra_achievable_html import (constants_context,  # noqa: E402
                                      offsets_context)


def cell_text(cell):
    return cell['text'] if isinstance(cell, dict) else str(cell)

TMP = tempfile.mkdtemp(prefix='penumbra-report-achievable.')
BASE = os.path.join(TMP, 'base')
fx.write_fixture(BASE, scenes=fx.SCENES[:1], lights=fx.LIGHTS[:1],
                 methods=fx.METHODS[:6])


def study(name, doc=None):
    """A copy of the base study, with doc as its fit/fit.json (None:
    without one); returns its folder."""
    path = os.path.join(TMP, name)
    shutil.copytree(BASE, path)
    if doc is not None:
        ff.write_fit(path, doc)
    return path


def run(*args):
    return subprocess.run(['/usr/bin/python3', REPORT] + list(args), text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def page_of(path):
    r = run('report', path)
    assert r.returncode == 0, r.stderr
    with open(os.path.join(path, 'report.html'), encoding='utf-8') as f:
        return f.read()


def pct(iv):
    """fit.json's [value, low, high] as the page shows it, in %."""
    return '{:.2f} [{:.2f}, {:.2f}]'.format(*(x * 100 for x in iv))


def rows_of(page, table_id):
    """The rows of a table of the page, each a list of cell texts."""
    start = page.index(f'id="{table_id}"')
    body = page[start:page.index('</table>', start)]
    return [[re.sub(r'<[^>]+>', '', c) for c in
             re.findall(r'<td[^>]*>(.*?)</td>', row)]
            for row in re.findall(r'<tr>(.*?)</tr>', body, re.S)][1:]


class Section(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.doc = ff.fit_doc(tie=True)
        cls.pages = {'absent': page_of(study('absent')),
                     'tie': page_of(study('tie', cls.doc)),
                     'apart': page_of(study('apart', ff.fit_doc(tie=False)))}

    def test_section_iff_fit_json(self):
        absent = self.pages['absent']
        self.assertIn('<h2 id="achievable">What is achievable</h2>', absent)
        self.assertIn('No fit/fit.json in this study folder: `penumbra fit '
                      'STUDY` then `penumbra report STUDY`', absent)
        self.assertNotIn('id="achievable-families"', absent)
        self.assertNotIn('achievable-share.png', absent)
        for name in ('tie', 'apart'):
            self.assertIn('id="achievable-families"', self.pages[name])
            self.assertNotIn('No fit/fit.json', self.pages[name])

    def test_numbers_are_fit_json(self):
        page, d = self.pages['tie'], self.doc
        self.assertIn(f'E* = {pct(d["floor"]["floor"])} % of albedo·E/π',
                      page)
        self.assertIn(f'raw bump: E = {pct(d["floor"]["none"])} % of '
                      'albedo·E/π', page)
        self.assertEqual(rows_of(page, 'achievable-families'), [
            [f['scope'], str(f['variants']), pct(f['floor']), pct(f['none'])]
            for f in d['family_floors']])
        shares = rows_of(page, 'achievable-shares')
        for row, m in zip(shares, d['methods']):
            self.assertEqual(row[0].rstrip(' †'), m['method'])
            self.assertEqual(row[1:], [pct(m['error']), '{:.2f} [{:.2f}, '
                                       '{:.2f}]'.format(*m['share'])])
        k = d['constants'][0]['fitted']
        self.assertIn('k = {:.3f} [{:.3f}, {:.3f}]'.format(*k), page)
        self.assertIn('against the published 0.125; the published constant '
                      'lies outside the interval.', page)
        # A constant no paper publishes is fitted against the study's own.
        self.assertIn("s = 0.075 [0.050, 0.125] (dimensionless; 95 % "
                      "bootstrap interval over variants) against the "
                      "study&#39;s value 0.3; the study&#39;s value lies "
                      "outside the interval.", page)
        self.assertIn('shading-offset are refitted among the values their '
                      'rows name', page)

    def test_image_floors_are_fit_json(self):
        page, im = self.pages['tie'], self.doc['image_floor']
        self.assertIn(f'raw bump {pct(im["none"])} % of albedo·E/π; a factor '
                      'of the light angle and deviation fitted to each '
                      f'variant alone reaches {pct(im["floor"])}.', page)
        self.assertIn('The lowest shipped method, mitsuba3, reaches '
                      f'{pct(im["methods"][0]["error"])}: 0.38 [0.27, 0.50] '
                      'of the floors&#39; gain on raw bump, above every '
                      'other method&#39;s share', page)
        self.assertEqual(rows_of(page, 'achievable-image'), [
            [m['method'] + (' †' if m['method'] == 'chiang2019' else ''),
             pct(m['error']), '{:.2f} [{:.2f}, {:.2f}]'.format(*m['share'])]
            for m in im['methods']])
        self.assertIn('predates the image floors: run penumbra fit STUDY '
                      'again', self.pages['apart'])
        self.assertNotIn('id="achievable-image"', self.pages['apart'])

    def test_offset_parameters_are_fit_json(self):
        page, offsets = self.pages['tie'], self.doc['offset_parameters']
        eps, cut = offsets
        self.assertIn(
            'epsilon: distance [scene units] refitted among 4 rendered '
            'values, over 24 low-poly variants: distance = 0.030 [0.003, '
            "0.030] (95 % bootstrap interval over variants) against Penumbra"
            "&#39;s default 0.01. Chosen without each scene, E = "
            f'{pct(eps["error_fitted_held_out"])} % of albedo·E/π against '
            f'{pct(eps["error_published"])} at Penumbra&#39;s default: '
            '-0.06 [-0.32, 0.22] percentage points, paired, a tie.', page)
        self.assertIn('cycles-geometry-offset: cutoff', page)
        self.assertIn('Blender&#39;s default lower.', page)
        rows = rows_of(page, 'achievable-offsets')
        self.assertEqual(rows, [
            [o['offset'], '{:g}'.format(v['value']), pct(v['error']),
             ', '.join(m for m, hit in (
                 ('fitted', v['value'] == o['fitted'][0]),
                 (o['reference'], v['value'] == o['published'])) if hit)
             .replace("'", '&#39;')]
            for o in offsets for v in o['values']])
        self.assertNotIn('id="achievable-offsets"', self.pages['apart'])

    def test_one_family_has_no_held_out_error(self):
        # fit.json writes null where the variants are of one family (or,
        # low-poly, one scene): the page says so instead of an error.
        doc = copy.deepcopy(self.doc)
        for entry in doc['constants'][:1] + doc['offset_parameters'][:1]:
            entry['error_fitted_held_out'] = None
            entry['held_out_minus_published'] = None
        path = os.path.join(TMP, 'one-family.json')
        with open(path, 'w') as f:
            json.dump(doc, f)
        fit = load_fit(path)
        offsets = offsets_context(fit)
        self.assertIn('no held-out error: the variants are of one scene',
                      offsets['sentences'][0])
        self.assertIn('Chosen without each scene', offsets['sentences'][1])
        row = constants_context(fit)['table']['rows'][0]
        self.assertEqual([cell_text(x) for x in row[5:8]],
                         ['none: one family', 'n/a', 'n/a'])

    def test_truths_left_out_are_named(self):
        self.assertIn('Left out of every fit: 2 variants whose ground truth '
                      'did not converge (v007, v011).', self.pages['tie'])
        self.assertNotIn('Left out of every fit', self.pages['apart'])

    def test_deshmukh2020_line_is_fit_json(self):
        page, d = self.pages['tie'], self.doc
        d0, d1 = [c for c in d['constants'] if c['method'] == 'deshmukh2020']
        self.assertIn(
            'deshmukh2020: fitted together in d = d0 + (d1 - d0) cos(delta): '
            'd0 = {:.4f} [{:.4f}, {:.4f}], '.format(*d0['fitted']) +
            'd1 = {:.4f} [{:.4f}, {:.4f}] '.format(*d1['fitted']) +
            '(dimensionless; 95 % bootstrap intervals over variants) against '
            'the published d0 = 0.1492, d1 = 0.01999; the published d0 lies '
            'inside its interval, the published d1 outside. The fit reached '
            'the edge of its range (d at deviation 60 degrees = 1): E would '
            'fall further beyond it, and the intervals hold within it.', page)
        rows = [r for r in rows_of(page, 'achievable-constants')
                if r[0].startswith('deshmukh2020')]
        self.assertEqual([r[0] for r in rows],
                         ['deshmukh2020 d0', 'deshmukh2020 d1'])
        for row, c in zip(rows, (d0, d1)):
            self.assertEqual(row[3:], [
                'yes' if c is d0 else 'no', pct(c['error_published']),
                pct(c['error_fitted_held_out']),
                pct(c['held_out_minus_published']['difference']), 'tie',
                pct(c['error_fitted_in_sample'])])
        k = [r for r in rows_of(page, 'achievable-constants')
             if r[0] == 'estevez2019'][0]
        self.assertEqual(k[6:8], [pct(d['constants'][0][
            'held_out_minus_published']['difference']), 'fitted lower'])

    def test_held_out_is_the_fitted_figure(self):
        rows = rows_of(self.pages['tie'], 'achievable-held-out')
        for row, h in zip(rows, self.doc['held_out']):
            self.assertEqual(row[:6], [
                h['family'], str(h['variants']), pct(h['held_out']),
                h['best_method'], pct(h['best']), pct(h['none'])])
            self.assertEqual(row[6], pct(h['held_out_minus_best']['difference']))
            self.assertEqual(row[8], f'{h["in_sample_floor"] * 100:.2f}')
        self.assertIn('in-sample (the study floor, fitted with the family)',
                      self.pages['tie'])

    def test_share_groups_are_fit_json(self):
        # The fixture's mitsuba3 overlaps chiang2019's interval but is not
        # tied with it paired: a rule by overlap would put it in group 1.
        fit = load_fit(os.path.join(TMP, 'tie', 'fit', 'fit.json'))
        self.assertEqual([(p['method'], p['group'], p['leader'])
                          for p in share_groups(fit['methods'])],
                         [('chiang2019', 1, 'chiang2019'),
                          ('mitsuba3', 2, 'mitsuba3'),
                          ('estevez2019', 2, 'mitsuba3'),
                          ('shading-offset(s=0.3)', 3,
                           'shading-offset(s=0.3)')])

    def test_report_writes_both_figures(self):
        figs = os.listdir(os.path.join(TMP, 'tie', 'figures'))
        for name in ('achievable-share', 'achievable-contour'):
            for ext in ('png', 'svg', 'pdf'):
                self.assertIn(f'{name}.{ext}', figs)

    def test_tie_rule(self):
        tie, apart = self.pages['tie'], self.pages['apart']
        pooled = self.doc['held_out_pooled']
        self.assertIn(f'fitted table held out by scene family has E = '
                      f'{pct(pooled)}', tie)
        self.assertIn('Paired over the same resamples, held-out minus '
                      'chiang2019 is 0.20 [-0.30, 0.70] percentage points: '
                      'the interval holds 0, so the held-out table and '
                      'chiang2019 are tied.', tie)
        # The two errors' own intervals overlap in `apart`: the paired
        # difference, not the overlap, decides.
        self.assertIn('held-out minus chiang2019 is -0.60 [-0.90, -0.30] '
                      'percentage points: the interval excludes 0, and the '
                      'held-out table is lower.', apart)
        self.assertNotIn('are tied', apart)
        self.assertIn('Per held-out family, against the best shipped method '
                      'there: fitted table lower in 1, tie in 1 (of 2).', tie)
        verdicts = [r[7] for r in rows_of(tie, 'achievable-held-out')]
        self.assertEqual(verdicts, ['tie', 'fitted table lower'])


class Figures(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.study = study('figures', ff.fit_doc())
        cls.dir = os.path.join(TMP, 'figure-out')
        os.makedirs(cls.dir)

    def test_same_bytes(self):
        for kind in ('achievable-share', 'achievable-contour'):
            for ext in ('pdf', 'svg', 'png'):
                paths = [os.path.join(self.dir, f'{kind}-{k}.{ext}')
                         for k in range(2)]
                for p in paths:
                    r = run('figure', self.study, '--kind', kind, '-o', p)
                    self.assertEqual(r.returncode, 0, r.stderr)
                    self.assertEqual(r.stdout.strip(), p)
                with open(paths[0], 'rb') as a, open(paths[1], 'rb') as b:
                    self.assertEqual(a.read(), b.read(), f'{kind} {ext}')

    def test_paper_width(self):
        for kind in ('achievable-share', 'achievable-contour'):
            for cols, width in (('1', 3.5), ('2', 7.0)):
                path = os.path.join(self.dir, f'paper-{kind}-{cols}.pdf')
                r = run('figure', self.study, '--kind', kind, '--style',
                        'paper', '--columns', cols, '-o', path)
                self.assertEqual(r.returncode, 0, r.stderr)
                with open(path, 'rb') as f:
                    box = re.search(rb'/MediaBox\s*\[\s*([\d.]+)\s+[\d.]+\s+'
                                    rb'([\d.]+)', f.read())
                x0, x1 = (float(v) for v in box.groups())
                self.assertAlmostEqual((x1 - x0) / 72, width, places=2)


def broken(edit):
    """fit_doc with one edit applied."""
    doc = copy.deepcopy(ff.fit_doc())
    edit(doc)
    return doc


BAD = [  # (name, fit.json document or text, the pointer named)
    ('no-floor', broken(lambda d: d.pop('floor')), '/floor'),
    ('short-share', broken(lambda d: d['methods'][1].update(share=[0.5, 0.4])),
     '/methods/1/share'),
    ('string-variants', broken(lambda d: d.update(variants='36')),
     '/variants'),
    ('family-none', broken(lambda d: d['family_floors'][0].pop('none')),
     '/family_floors/0/none'),
    ('rows', broken(lambda d: d['pictures']['g']['floor'].pop()),
     '/pictures/g/floor'),
    ('row-length', broken(lambda d: d['pictures']['g']['fitted'][3].pop()),
     '/pictures/g/fitted'),
    ('light-order', broken(lambda d: d['pictures']['light_deg'].reverse()),
     '/pictures/light_deg'),
    ('held-out-best', broken(lambda d: d['held_out'][1].update(best=None)),
     '/held_out/1/best'),
    # a fit.json from before paired differences
    ('no-paired', broken(lambda d: d['constants'][0].pop(
        'held_out_minus_published')), '/constants/0/held_out_minus_published'),
    ('paired-tie', broken(lambda d: d['held_out_minus_best'].update(tie=1)),
     '/held_out_minus_best/tie'),
    ('malformed', '{"floor": ', 'malformed JSON')]


class BadFitJson(unittest.TestCase):
    def test_report_and_figure_refuse(self):
        out = os.path.join(TMP, 'bad-out')
        os.makedirs(out)
        for name, doc, where in BAD:
            path = study('bad-' + name, doc if isinstance(doc, dict) else {})
            fit = os.path.join(path, 'fit', 'fit.json')
            if not isinstance(doc, dict):
                with open(fit, 'w', encoding='utf-8') as f:
                    f.write(doc)
            before = sorted(os.listdir(path))
            r = run('report', path)
            self.assertEqual(r.returncode, 2, f'{name}: {r.stderr}')
            self.assertRegex(r.stderr, rf'^report\.py: {re.escape(fit)}: '
                             rf'{re.escape(where)}\S*[: ].*\n$', name)
            self.assertEqual(sorted(os.listdir(path)), before, name)
            for kind in ('achievable-share', 'achievable-contour'):
                r = run('figure', path, '--kind', kind, '-o',
                        os.path.join(out, f'{name}.pdf'))
                self.assertEqual(r.returncode, 2, f'{name}: {r.stderr}')
                self.assertRegex(r.stderr, rf'^report\.py: {re.escape(fit)}: '
                                 rf'{re.escape(where)}', name)
            self.assertEqual(os.listdir(out), [], name)

    def test_without_pictures(self):
        path = study('no-pictures', ff.fit_doc(with_pictures=False))
        r = run('figure', path, '--kind', 'achievable-contour', '-o',
                os.path.join(TMP, 'no-pictures.pdf'))
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r'^report\.py: \S*fit\.json: /pictures: ')
        self.assertFalse(os.path.exists(os.path.join(TMP, 'no-pictures.pdf')))
        r = run('figure', path, '--kind', 'achievable-share', '--x', '/a',
                '-o', os.path.join(TMP, 'x.pdf'))
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r'^report\.py: --x: does not apply')
        page = page_of(path)
        self.assertIn('has no "pictures"', page)
        self.assertNotIn('achievable-contour.png', page)
        # null: what penumbra fit writes for a grid of other inputs
        path = study('null-pictures', broken(
            lambda d: d.update(pictures=None)))
        page = page_of(path)
        self.assertIn('has no "pictures"', page)
        self.assertNotIn('achievable-contour.png', page)
        self.assertIn('achievable-share.png', page)


class MoreInputs(unittest.TestCase):
    """A fit of light, deviation and shading (penumbra fit --inputs): the
    section names its inputs, states the nested floor's gain in
    percentage points with its interval, and drops chiang2019's dagger
    (the floor of these inputs bounds it)."""

    def test_section_names_the_inputs_and_the_gain(self):
        doc = ff.fit_doc(with_pictures=False)
        doc['inputs'] = 'light,deviation,shading'
        doc['pictures'] = None
        doc['constants'] = []
        doc['nested_floors'] = [{
            'scope': 'study', 'variants': 36, 'kkt_residual': 1e-12,
            'inputs': 'light,deviation', 'floor': ff.iv(0.0330, 0.0240, 0.0420),
            'none': doc['floor']['none'],
            'gain': ff.paired(-0.0030, -0.0051, -0.0014)}]
        page = page_of(study('shading', doc))
        self.assertIn('one factor G of the light angle, deviation and '
                      'shading angle shared by all', page)
        self.assertIn('On the same grid, a factor of the light angle and '
                      'deviation alone reaches E* = 3.30 [2.40, 4.20] % of '
                      'albedo·E/π; the added inputs lower the floor by 0.30 '
                      '[0.14, 0.51] percentage points (paired over the same '
                      'resamples).', page)
        shares = rows_of(page, 'achievable-shares')
        self.assertEqual([r[0] for r in shares if r[0].endswith('†')], [])
        self.assertNotIn('also sees ⟨Ns,ωi⟩', page)
        # The default inputs keep the dagger.
        self.assertIn('chiang2019 †', page_of(study('plain', ff.fit_doc())))

    def test_a_nested_floor_without_its_gain_is_refused(self):
        doc = ff.fit_doc()
        doc['nested_floors'] = [dict(doc['floor'], inputs='light,deviation')]
        path = study('no-gain', doc)
        r = run('report', path)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertRegex(r.stderr, r'^report\.py: \S*fit\.json: '
                         r'/nested_floors/0/gain: expected')


if __name__ == '__main__':
    try:
        unittest.main(argv=[sys.argv[0]] + sys.argv[2:], verbosity=2)
    finally:
        shutil.rmtree(TMP, ignore_errors=True)
