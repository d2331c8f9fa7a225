#!/usr/bin/python3
"""The harness's paper figures, tables and page (issue 37), on synthetic
study folders (report_fixture.py), without the C++ binary.

Usage: test_report_paper.py SOURCE_DIR [unittest options]

Checks that
  - the palette tells 25 methods apart by colour and line style and by
    colour and marker, `none` grey, each method's look the same everywhere;
  - one reading of the rank groups (penumbra_stats.ranked) gives the same
    groups in the page's table, `report.py table`, and the ranking figure;
  - every figure's value-axis and colour-bar labels state the unit of the
    matching metrics.csv column (harness/csv-columns.json);
  - `report.py figure --style paper` writes a PDF exactly 3.5 or 7 in wide
    (its MediaBox), and the same bytes twice;
  - bad options and inputs: one line 'report.py: <file or option>: <what>',
    exit 2, nothing written;
  - `report.py table` in Markdown, CSV and LaTeX (booktabs, escaped); the
    LaTeX compiles with pdflatex where it is installed (Debian's
    texlive-latex-recommended), else that test is skipped, saying why;
  - the page: provenance, notices, statistics.headline then the rank-group
    table, the interaction sentence and per-level rank groups, escaping; an
    older report.json (no new fields) and a study without `none` (no
    ranking, and why) still give a page;
  - the variant sections: a balanced pick that covers every axis value.
"""
import csv
import io
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
HARNESS = os.path.join(SOURCE, 'harness')
REPORT = os.path.join(HARNESS, 'report.py')
sys.path[:0] = [HARNESS, os.path.dirname(os.path.abspath(__file__))]
sys.dont_write_bytecode = True

import report_fixture as fx  # noqa: E402
from penumbra_data import (  # noqa: E402
    CSV_COLUMNS, LP_COLUMNS, LP_PANELS, LP_SIDE, PRIMARY, Report, shown_variants)
from penumbra_figures import profile_fig, report_styles  # noqa: E402
from penumbra_paper_figures import (  # noqa: E402
    line_fig, mean_rmse_fig, ranking_fig, statistics_fig)
from penumbra_plot import plt  # noqa: E402
from penumbra_stats import MEAN_METRICS, Stats, ranked  # noqa: E402
from penumbra_style import SCREEN, Style, series_styles  # noqa: E402
from penumbra_sweeps import heatmap_fig  # noqa: E402
import penumbra_tables  # noqa: E402
from penumbra_tables import ranking_table  # noqa: E402

SMALL = dict(scenes=fx.SCENES[:1], lights=fx.LIGHTS[:1], methods=fx.METHODS[:8])
TMP = tempfile.mkdtemp(prefix='penumbra-report-paper.')


def folder(name, **kw):
    """A fixture study folder, written once per test run."""
    path = os.path.join(TMP, name)
    if not os.path.exists(path):
        fx.write_fixture(path, **kw)
    return path


def run(*args):
    return subprocess.run(['/usr/bin/python3', REPORT] + list(args), text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def unit_of(label):
    """The unit an axis label states: the text in its outermost last
    parentheses, with the figures' typography as the CSV writes it."""
    text = ' '.join(label.split())
    depth, start, last = 0, None, None
    for k, c in enumerate(text):
        if c == '(':
            depth, start = depth + 1, k if depth == 0 else start
        elif c == ')' and depth:
            depth -= 1
            if depth == 0:
                last = text[start + 1:k]
    for a, b in (('·', '*'), ('π', 'pi'), ('⁻²', '^-2'), ('⁻¹', '^-1')):
        last = (last or '').replace(a, b)
    return last


def csv_units():
    """{column: unit} of metrics.csv (csv-columns.json); the primary
    metric's from the contract while the C++ side has not added it."""
    with open(os.path.join(HARNESS, 'csv-columns.json'), encoding='utf-8') as f:
        doc = json.load(f)
    units = {c['name']: c['unit'] for c in doc['files']['metrics.csv']['columns']
             if 'name' in c}
    units.setdefault(PRIMARY, "fraction of raw bump's E_term + E_view in the same variant")
    return units


def labels(fig):
    """Every axis and colour-bar label of a figure (y labels of the value
    axes, x labels; empty ones left out)."""
    out = []
    for ax in fig.axes:
        out += [t for t in (ax.get_xlabel(), ax.get_ylabel()) if t.strip()]
    return out


class Palette(unittest.TestCase):
    def test_25_methods_apart_and_none_grey(self):
        names = ['none'] + [f'm{k}' for k in range(24)]
        st = series_styles(names)
        looks = [(v['color'], str(v['ls'])) for k, v in st.items() if k != 'none']
        marks = [(v['color'], v['marker']) for k, v in st.items() if k != 'none']
        self.assertEqual(len(set(looks)), 24)
        self.assertEqual(len(set(marks)), 24)
        self.assertEqual(st['none']['color'], (0.5, 0.5, 0.5))
        # A method's look depends on its place in the report's list only.
        self.assertEqual(series_styles(names)['m7'], st['m7'])


class RankGroups(unittest.TestCase):
    """The same rank groups in the page, the table command and the figure."""

    @classmethod
    def setUpClass(cls):
        cls.out = folder('new')
        cls.report = Report(cls.out)
        cls.stats = Stats(cls.report)
        cls.expected = {r['method']: r['group'] for r in ranked(cls.stats.overall)}

    def test_table_command(self):
        r = run('table', self.out, '--format', 'csv')
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = list(csv.DictReader(io.StringIO(r.stdout)))
        self.assertEqual({x['method']: int(x['rank_group']) for x in rows}, self.expected)
        self.assertEqual([x['method'] for x in rows], list(self.expected))

    def test_figure(self):
        fig = ranking_fig(self.stats, report_styles(self.report, self.stats), SCREEN)
        ax = fig.axes[0]
        names = {round(y, 3): t.get_text() for y, t in zip(ax.get_yticks(),
                                                            ax.get_yticklabels())}
        found = {int(m.group(1)): t.get_position()[1] for t in ax.texts
                 for m in [re.fullmatch(r'group (\d+)', t.get_text())] if m}
        plt.close(fig)
        self.assertEqual(sorted(found), sorted(set(self.expected.values())))
        for g, y in found.items():
            # A group's label sits at the middle of exactly its rows.
            ys = [ty for ty, name in names.items() if self.expected[name] == g]
            self.assertAlmostEqual((min(ys) + max(ys)) / 2, y)

    def test_page_table_matches(self):
        head, rows = ranking_table(self.stats)['head'], ranking_table(self.stats)['rows']
        self.assertEqual(head[0][0], 'rank group')
        self.assertEqual({r[1]: r[0] for r in rows}, self.expected)


class Units(unittest.TestCase):
    """Every value axis states the unit of its metric's CSV column."""

    @classmethod
    def setUpClass(cls):
        cls.report = Report(folder('new'))
        cls.stats = Stats(cls.report)
        cls.styles = report_styles(cls.report, cls.stats)
        cls.units = csv_units()

    def check(self, fig, metric, where):
        want = self.units[CSV_COLUMNS[metric]]
        got = [unit_of(t) for t in labels(fig)]
        plt.close(fig)
        self.assertIn(want, got, f'{where}: {metric}: labels {got}')

    def test_line_and_ranking_figures(self):
        methods = ['none', 'chiang2019', 'estevez2019']
        for metric in MEAN_METRICS:
            for axis in self.stats.by_axis():
                self.check(line_fig(self.stats, axis, metric, methods, self.styles, SCREEN),
                           metric, f'line {axis["pointer"]}')
            self.check(ranking_fig(self.stats, self.styles, SCREEN, None, metric),
                       metric, 'ranking')
        self.check(statistics_fig(self.stats, self.styles, SCREEN), PRIMARY, 'statistics')
        self.check(mean_rmse_fig(self.stats, self.styles, SCREEN),
                   'profile.rmse_terminator', 'mean-rmse-terminator')

    def test_heatmaps(self):
        for metric in ('profile.rmse_terminator', 'profile.position_error_deg', 'image.rmse'):
            fig = heatmap_fig(self.report.doc, self.report.src,
                              {'metric': metric, 'x': 0, 'y': 1, 'kind': 'heatmap',
                               'renderer': 'evaluator'}, None, ['none', 'chiang2019'], SCREEN)
            self.check(fig, metric, 'heatmap')

    def test_profiles(self):
        fig = profile_fig(self.report.variants[0], self.styles, self.report.terminator)
        got = {unit_of(t) for t in labels(fig)}
        plt.close(fig)
        # L and its difference: the profile columns' unit; theta: degrees.
        self.assertTrue({self.units['profile_rmse_terminator_rel'], 'degrees'} <= got, got)


class LowPolyUnits(unittest.TestCase):
    def test_panels_state_the_csv_unit(self):
        with open(os.path.join(HARNESS, 'csv-columns.json'), encoding='utf-8') as f:
            cols = {c['name']: c['unit'] for c in json.load(f)['files']['lowpoly.csv']['columns']
                    if 'name' in c}
        for metric, name, unit, scale in LP_PANELS + LP_SIDE:
            # The figures' y label is f'{name} ({unit})' of values * scale.
            self.assertEqual(unit_of(f'{name} ({unit})'), cols[LP_COLUMNS[metric]], metric)
            self.assertEqual(scale, 1, metric)


def media_box(path):
    with open(path, 'rb') as f:
        m = re.search(rb'/MediaBox\s*\[\s*([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s*\]',
                      f.read())
    return [float(x) for x in m.groups()]


class FigureCommand(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out = folder('new')
        cls.dir = os.path.join(TMP, 'figure-command')
        os.makedirs(cls.dir, exist_ok=True)

    def test_paper_pdf_width(self):
        for kind in ('line', 'ranking', 'profile', 'heatmap'):
            for cols, width in (('1', 3.5), ('2', 7.0)):
                path = os.path.join(self.dir, f'{kind}-{cols}.pdf')
                r = run('figure', self.out, '--kind', kind, '--style', 'paper',
                        '--columns', cols, '-o', path)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertEqual(r.stdout.strip(), path)
                x0, _, x1, _ = media_box(path)
                self.assertAlmostEqual((x1 - x0) / 72, width, places=2, msg=f'{kind} {cols}')

    def test_same_bytes(self):
        for ext in ('pdf', 'svg', 'png'):
            paths = [os.path.join(self.dir, f'same-{k}.{ext}') for k in range(2)]
            for p in paths:
                r = run('figure', self.out, '--kind', 'line', '--x', '/height/amplitude',
                        '--methods', 'none,chiang2019,estevez2019,mitsuba3',
                        '--style', 'paper', '-o', p)
                self.assertEqual(r.returncode, 0, r.stderr)
            with open(paths[0], 'rb') as a, open(paths[1], 'rb') as b:
                self.assertEqual(a.read(), b.read(), ext)

    def test_errors(self):
        target = os.path.join(self.dir, 'never.pdf')
        cases = [
            (['--kind', 'line', '--methods', 'none,nosuch', '-o', target], '--methods'),
            (['--kind', 'pie', '-o', target], '--kind'),
            (['--kind', 'line', '-o', os.path.join(self.dir, 'x.jpg')], '-o'),
            (['--kind', 'line'], '-o'),
            (['--kind', 'line', '--x', '/no/axis', '-o', target], '--x'),
            (['--kind', 'line', '--style', 'poster', '-o', target], '--style'),
            (['--kind', 'line', '--columns', '3', '-o', target], '--columns'),
            (['--kind', 'line', '--bogus', '1', '-o', target], '--bogus'),
            (['--kind', 'profile', '--variant', 'v999', '-o', target], '--variant'),
            (['--kind', 'line', '--metric', 'image.mask_iou', '-o', target], '--metric'),
            (['--kind', 'line', '-o', os.path.join(self.dir, 'no', 'such.pdf')], '-o')]
        for args, what in cases:
            before = set(os.listdir(self.dir))
            r = run('figure', self.out, *args)
            self.assertEqual(r.returncode, 2, f'{args}: {r.stderr}')
            self.assertRegex(r.stderr, rf'^report\.py: {re.escape(what)}: \S.*\n$', args)
            self.assertEqual(set(os.listdir(self.dir)), before, f'{args} wrote something')
        r = run('figure', os.path.join(TMP, 'no-study'), '--kind', 'line', '-o', target)
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r'^report\.py: \S*report\.json: no such file\n$')


class TableCommand(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out = folder('new')

    def table(self, *args):
        r = run('table', self.out, *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        return r.stdout

    def test_markdown_and_csv(self):
        md = self.table('--format', 'markdown')
        self.assertIn('| rank group | method | combined error C', md)
        self.assertRegex(md, r'\| 1 \| estevez2019 \| 0\.70\d? \[0\.6\d+, 0\.7\d+\] \| leader \|')
        self.assertIn('Rank groups: A rank group is', md)
        by = self.table('--format', 'markdown', '--by', '/height/amplitude')
        row = next(l for l in by.splitlines() if l.startswith('| chiang2019 '))
        cells = [c.strip() for c in row.strip('|').split('|')]
        # Worse than raw bump at A = 0.005, the best group at A = 0.02.
        self.assertRegex(cells[1], r'^1\.6\d* \[.*\] \(g\d\)$')
        self.assertTrue(cells[3].endswith('(g1)'), cells)
        rows = list(csv.DictReader(io.StringIO(
            self.table('--format', 'csv', '--by', 'shading'))))
        self.assertEqual({r['level'] for r in rows}, {'lambert', 'ggx-diffuse', 'ggx-all'})
        self.assertTrue(all(float(r['ci_low']) <= float(r['value']) <= float(r['ci_high'])
                            for r in rows))

    def test_latex_escapes(self):
        tex = self.table('--format', 'latex')
        self.assertIn('\\toprule', tex)
        self.assertIn('shading-offset(s=0.3)', tex)
        self.assertIn('method\\_06', tex)
        body = tex.split('\\midrule', 1)[1]  # the rows (the head is ours, in math)
        for line in body.splitlines():
            self.assertIsNone(re.search(r'(?<!\\)[_%#]', line), line)
        self.assertIn('E\\_term', tex)
        self.assertEqual(penumbra_tables.tex('a_b & 50% #1 {x} ~ π·°'),
                         r'a\_b \& 50\% \#1 \{x\} \textasciitilde{} $\pi$$\cdot$$^\circ$')

    def test_latex_compiles(self):
        pdflatex = shutil.which('pdflatex')
        if pdflatex is None:
            self.skipTest('pdflatex is not installed (Debian: apt-get install '
                          'texlive-latex-recommended)')
        work = tempfile.mkdtemp(dir=TMP)
        body = self.table('--format', 'latex') + self.table(
            '--format', 'latex', '--by', '/height/amplitude')
        with open(os.path.join(work, 't.tex'), 'w', encoding='utf-8') as f:
            f.write('\\documentclass{article}\\usepackage{booktabs}\n'
                    '\\usepackage[margin=1cm,landscape]{geometry}\n'
                    '\\begin{document}\n' + body + '\\end{document}\n')
        r = subprocess.run([pdflatex, '-interaction=nonstopmode', '-halt-on-error', 't.tex'],
                           cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           text=True)
        self.assertEqual(r.returncode, 0, r.stdout[-2000:])
        self.assertTrue(os.path.exists(os.path.join(work, 't.pdf')))

    def test_errors(self):
        for args, what in ((['--format', 'html'], '--format'),
                           (['--by', '/height/amplitude'], '--format'),
                           (['--format', 'csv', '--by', '/nope'], '--by'),
                           (['--format', 'csv', '--by', 'shading', '--metric', 'x'],
                            '--metric'),
                           (['--format', 'csv', '--bogus', 'x'], '--bogus')):
            r = run('table', self.out, *args)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertRegex(r.stderr, rf'^report\.py: {re.escape(what)}: \S.*\n$')
            self.assertEqual(r.stdout, '')


class Page(unittest.TestCase):
    """report.html of a small study with the new fields, an older one, and
    one without `none`."""

    @classmethod
    def setUpClass(cls):
        cls.pages = {}
        for name, kw in (('page-new', {}), ('page-old', {'new_fields': False}),
                         ('page-nonone', {'with_none': False})):
            out = folder(name, **dict(SMALL, **kw))
            r = run('report', out)
            assert r.returncode == 0, r.stderr
            with open(os.path.join(out, 'report.html'), encoding='utf-8') as f:
                cls.pages[name] = f.read()

    def test_headline_then_rank_groups(self):
        page = self.pages['page-new']
        first = page.index('estevez2019 leads the best rank group.')
        self.assertLess(first, page.index('id="methods-table"'))
        self.assertLess(page.index('At A = 0.02 chiang2019'), page.index('id="methods-table"'))
        self.assertIn('A rank group is the best method not yet grouped', page)

    def contains(self, name, *texts):
        for t in texts:
            self.assertIn(t, self.pages[name])

    def test_provenance_notices_escaping(self):
        self.contains('page-new', '<summary>Provenance</summary>', 'Test CPU &lt;script&gt;',
                      'fixture &lt;b&gt;&amp;amp;', '2026-11-27T06:00:00Z')
        self.assertNotIn('<script>', self.pages['page-new'])

    def test_interactions_and_levels(self):
        self.contains('page-new', 'chiang2019: its effect depends on amplitude A (scene units)',
                      'figures/line-height-amplitude.{png,svg,pdf}', 'not the ranking metric',
                      'The mean absolute terminator RMSE orders chiang2019 differently')

    def test_older_report(self):
        self.contains('page-old', 'records no provenance', 'id="methods-table"',
                      'no statistics.by_axis')

    def test_without_none(self):
        page = self.pages['page-nonone']
        self.assertIn('No ranking: this report.json has no ranking statistics', page)
        self.assertIn('The study names no raw bump (`none`): its ranking is skipped.', page)
        r = run('table', os.path.join(TMP, 'page-nonone'), '--format', 'csv')
        self.assertEqual(r.returncode, 2)
        self.assertIn('no raw bump', r.stderr)
        r = run('figure', os.path.join(TMP, 'page-nonone'), '--kind', 'ranking', '-o',
                os.path.join(TMP, 'nonone.pdf'))
        self.assertEqual(r.returncode, 2)
        self.assertFalse(os.path.exists(os.path.join(TMP, 'nonone.pdf')))

    def test_units_in_headings(self):
        # Percent only where the heading says so: every "%" cell's column
        # heading carries "%".
        for page in self.pages.values():
            for table in re.findall(r'<table>.*?</table>', page, re.S):
                heads = re.findall(r'<th>(.*?)</th>', table.split('</tr>')[0])
                for row in re.findall(r'<tr>(.*?)</tr>', table, re.S)[1:]:
                    for head, cell in zip(heads, re.findall(r'<td[^>]*>(.*?)</td>', row)):
                        if cell.rstrip().endswith('%'):
                            self.assertIn('%', head, cell)


class Sections(unittest.TestCase):
    def test_balanced_pick(self):
        vs = fx.variants()
        shown = shown_variants(vs, 48)
        self.assertEqual(len(shown), 48)
        for k in range(3):
            counts = {}
            for v in shown:
                key = json.dumps(v['axis_values'][k])
                counts[key] = counts.get(key, 0) + 1
            self.assertEqual(len(counts), len({json.dumps(v['axis_values'][k]) for v in vs}))
            self.assertLessEqual(max(counts.values()) - min(counts.values()), 1, counts)

    def test_paper_style_sizes(self):
        for cols, width in ((1, 3.5), (2, 7.0)):
            self.assertEqual(Style('paper', cols).width(11), width)
        self.assertEqual(Style('screen').width(11), 11)


if __name__ == '__main__':
    try:
        unittest.main(argv=[sys.argv[0]] + sys.argv[2:], verbosity=2)
    finally:
        shutil.rmtree(TMP, ignore_errors=True)
