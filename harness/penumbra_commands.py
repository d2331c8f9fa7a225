"""`report.py figure` and `report.py table`: one figure or one table
redrawn from a finished study's report.json, without rendering (the C++
side's `penumbra figure` and `penumbra table` run these).

Every option is checked, and the study read, before anything is drawn: a
bad option or input is one line 'report.py: <file or option>: <what>', exit
status 2, and nothing written (the output file is written under a
temporary name and renamed when complete).
"""
import os

from penumbra_achievable import (
    contour_fig, fit_path, load_fit, share_fig)
from penumbra_data import METRICS, PRIMARY, BadInput, Report, objs
from penumbra_grid_figure import grid_fig
from penumbra_plot import replacing
from penumbra_figures import (
    figure_methods, profile_fig, report_methods, report_styles)
from penumbra_paper_figures import line_fig, ranking_fig
from penumbra_stats import MEAN_METRICS, Stats, line_methods
from penumbra_style import Style, write_figure
from penumbra_sweeps import heatmap_fig
from penumbra_tables import (
    csv_text, latex, level_table, markdown, ranking_table, table_caption)

ACHIEVABLE = ('achievable-share', 'achievable-contour')
FIGURE_OPTIONS = ('--kind', '--x', '--y', '--metric', '--methods',
                  '--variant', '--scene', '--style', '--columns', '-o')
TABLE_OPTIONS = ('--format', '--by', '--metric', '-o')
KINDS = ('line', 'profile', 'ranking', 'heatmap', 'grid') + ACHIEVABLE
# What an achievable kind takes: it draws STUDY/fit/fit.json alone.
ACHIEVABLE_OPTIONS = ('--kind', '--style', '--columns', '-o')


def parse(argv, allowed):
    """{option: value} of '--opt value' or '--opt=value' pairs."""
    opts, k = {}, 0
    while k < len(argv):
        opt, _, value = argv[k].partition('=')
        if opt not in allowed:
            raise BadInput(opt, 'unknown option (known: ' +
                           ', '.join(allowed) + ')')
        if not _:
            if k + 1 >= len(argv):
                raise BadInput(opt, 'needs a value')
            k, value = k + 1, argv[k + 1]
        if opt in opts:
            raise BadInput(opt, 'given twice')
        opts[opt], k = value, k + 1
    return opts


def choice(opts, opt, allowed, default=None):
    value = opts.get(opt, default)
    if value not in allowed:
        raise BadInput(opt, f'{value!r} is not one of ' + ', '.join(
            str(a) for a in allowed) if value is not None else
            'is required (' + ', '.join(allowed) + ')')
    return value


def output_path(opts, exts):
    """-o's path, checked: its extension, and a folder that exists."""
    path = opts.get('-o')
    if path is None:
        return None
    ext = os.path.splitext(path)[1][1:].lower()
    if exts and ext not in exts:
        raise BadInput('-o', f'{path}: the extension must be one of ' +
                       ', '.join('.' + e for e in exts))
    if not os.path.isdir(os.path.dirname(os.path.abspath(path))):
        raise BadInput('-o', f'{path}: no such folder')
    return path


def method_list(opts, report, stats):
    """--methods as a list, each one the study has (None: the default
    handful, penumbra_stats.highlighted; 'all': every method)."""
    known = report_methods(report)
    value = opts.get('--methods')
    if value is None:
        return figure_methods(report, stats)
    if value == 'all':
        return known
    names = [m.strip() for m in value.split(',') if m.strip()]
    bad = [m for m in names if m not in known]
    if bad or not names:
        what = f'unknown method {bad[0]!r}' if bad else 'no method named'
        raise BadInput('--methods', f'{what} (this study\'s: '
                       f'{", ".join(known)})')
    return list(dict.fromkeys(names))


def axis_of(stats, opts, opt='--x'):
    """The option's axis pointer as a by_axis entry (default: the first
    axis)."""
    axes = stats.by_axis()
    pointer = opts.get(opt, axes[0]['pointer'] if axes else None)
    axis = stats.axis(pointer) if pointer is not None else None
    if axis is None:
        raise BadInput(opt, f'no axis {pointer!r} (this study\'s: ' +
                       ', '.join(a['pointer'] for a in axes) + ')')
    return axis


def figure_of(kind, opts, report, stats, style):
    """The Figure a `figure` command asks for (every option checked)."""
    styles = report_styles(report, stats)
    methods = method_list(opts, report, stats)
    if kind == 'line':
        metric = choice(opts, '--metric', MEAN_METRICS, PRIMARY)
        axis = axis_of(stats, opts)
        if '--methods' not in opts:
            methods = line_methods(methods, axis)
        return line_fig(stats, axis, metric, methods, styles, style)
    if kind == 'ranking':
        if not stats.rows:
            raise BadInput(report.src, 'no ranking statistics (the study '
                           'names no raw bump `none`, or has no variants)')
        metric = choice(opts, '--metric', MEAN_METRICS, PRIMARY)
        return ranking_fig(stats, styles, style, opts.get('--methods') and
                           methods, metric)
    if kind in ('profile', 'grid'):
        ids = [str(v.get('id')) for v in report.variants]
        var = report.variants[ids.index(
            choice(opts, '--variant', ids, ids[0] if ids else None))]
        if kind == 'profile':
            return profile_fig(var, styles, report.terminator, methods,
                               style, marks=len(methods) > 5)
        fig = grid_fig(var, report.out, report.src,
                       [str(r.get('id')) for r in report.renderers],
                       None if opts.get('--methods') == 'all' else methods,
                       style.width(None))
        if fig is None:
            raise BadInput('--variant', f'{var.get("id")} has no images')
        return fig
    return heatmap_of(opts, report, methods, style)


def heatmap_of(opts, report, methods, style):
    """The heatmap figure: --x and --y pointers (default: the study's
    first plot, else its first two axes), --metric (a comparison metric),
    --scene (default: every scene pooled)."""
    axes = objs(report.doc.get('axes'))
    pointers = [str(a.get('pointer')) for a in axes]
    plots = objs(report.doc.get('plots'))
    first = plots[0] if plots else {'x': 0, 'y': 1}
    plot = {'kind': 'heatmap', 'renderer': first.get('renderer', 'evaluator')}
    for key, opt in (('x', '--x'), ('y', '--y')):
        i = first.get(key)
        default = pointers[i] if type(i) is int and i < len(pointers) else None
        p = choice(opts, opt, pointers, default)
        plot[key] = pointers.index(p)
    plot['metric'] = choice(opts, '--metric', [m for m in METRICS
                                               if m != PRIMARY],
                            first.get('metric', 'profile.rmse_terminator'))
    scenes = sorted({str(v.get('scene')) for v in report.variants})
    scene = opts.get('--scene')
    if scene is not None:
        choice(opts, '--scene', scenes)
    fig = heatmap_fig(report.doc, report.src, plot, scene, methods, style)
    if fig is None:
        raise BadInput(report.src, f'no finite {plot["metric"]} over '
                       f'{pointers[plot["x"]]} x {pointers[plot["y"]]}')
    return fig


def figure_command(argv):
    """report.py figure OUT --kind K [options] -o FILE: returns [FILE]."""
    if not argv or argv[0].startswith('-'):
        raise BadInput('OUT', 'the study folder comes first')
    opts = parse(argv[1:], FIGURE_OPTIONS)
    kind = choice(opts, '--kind', KINDS)
    style = Style(choice(opts, '--style', ('screen', 'paper'), 'screen'),
                  int(choice(opts, '--columns', ('1', '2'), '2')))
    path = output_path(opts, ('pdf', 'svg', 'png'))
    if path is None:
        raise BadInput('-o', 'is required (FILE.pdf, .svg or .png)')
    if kind in ACHIEVABLE:
        return [achievable_figure(kind, opts, argv[0], style, path)], None
    report = Report(argv[0])
    with style.active():
        fig = figure_of(kind, opts, report, Stats(report), style)
    if fig is None:
        raise BadInput(report.src, f'no values to draw a {kind} figure '
                       'from (a study without raw bump `none` has no '
                       'combined error)')
    return [write_figure(fig, path, style)], None


def achievable_figure(kind, opts, study, style, path):
    """A figure of STUDY/fit/fit.json (penumbra fit's), not of report.json:
    the share chart, or the contour plot of G* (fit.json's pictures)."""
    extra = [o for o in opts if o not in ACHIEVABLE_OPTIONS]
    if extra:
        raise BadInput(extra[0], f'does not apply to --kind {kind}')
    fit = load_fit(fit_path(study))
    with style.active():
        fig = (share_fig if kind == 'achievable-share' else
               contour_fig)(fit, style)
    if fig is None:
        raise BadInput(fit['src'], '/pictures: absent or null (penumbra '
                       'fit writes it for a light,deviation grid; an older '
                       'one wrote none)' if kind == 'achievable-contour'
                       else '/methods: no method with a share')
    return write_figure(fig, path, style)


def table_command(argv):
    """report.py table OUT --format F [--by POINTER] [--metric M] [-o
    FILE]: returns ([FILE], None) or ([], the table's text)."""
    if not argv or argv[0].startswith('-'):
        raise BadInput('OUT', 'the study folder comes first')
    opts = parse(argv[1:], TABLE_OPTIONS)
    fmt = choice(opts, '--format', ('latex', 'markdown', 'csv'))
    path = output_path(opts, ())
    report = Report(argv[0])
    stats = Stats(report)
    if not stats.present:
        raise BadInput(report.src, 'no ranking statistics: the study names '
                       'no raw bump (`none`), the baseline every ranking '
                       'is relative to')
    if '--by' in opts:
        metric = choice(opts, '--metric', MEAN_METRICS, PRIMARY)
        table = level_table(stats, axis_of(stats, opts, '--by'),
                            metric)
    else:
        table = ranking_table(stats)
    cap = table_caption(stats, table)
    text = {'latex': lambda: latex(table, cap),
            'markdown': lambda: markdown(table, cap),
            'csv': lambda: csv_text(table)}[fmt]()
    if path is None:
        return [], text
    return [write_text(path, text)], None


def write_text(path, text):
    """text into path atomically (nothing left behind on an error)."""
    with replacing(path) as tmp, open(tmp, 'w', encoding='utf-8') as f:
        f.write(text)
    return path
