#!/usr/bin/python3
"""Figures and the HTML page of a Penumbra study: the entry
point (argument handling, exit status, messages); the work is done by
  penumbra_data.py      reading and checking report.json (and the low-poly
                        section's model)
  penumbra_stats.py     the ranking statistics (rank groups, by-axis
                        levels, the highlighted methods), with fall-backs
                        for older report.json files
  penumbra_plot.py, penumbra_style.py (screen and paper styles, the
  palette), penumbra_figures.py, penumbra_paper_figures.py,
  penumbra_sweeps.py, penumbra_grid_figure.py, penumbra_lowpoly_figures.py,
  penumbra_contour.py   the matplotlib figures
  penumbra_tables.py    the ranking and per-level tables (HTML, LaTeX,
                        Markdown, CSV)
  penumbra_commands.py  the figure and table commands
  penumbra_html.py, penumbra_lowpoly_html.py, penumbra_context.py
                        report.html's context, rendered by Jinja2 from
                        templates/ (report.html.j2 and what it includes)

Usage (Debian's Python, with python3-matplotlib and python3-jinja2):
  /usr/bin/python3 harness/report.py report OUT [--self-contained]
      reads OUT/report.json (and OUT/fit/fit.json when there: the "What
      is achievable" section); writes OUT/figures/*.{png,svg,pdf} and
      OUT/report.html, which links its images (relative URLs into
      OUT/images and OUT/figures: keep the folder together), or with
      --self-contained embeds every image as a data: URI (one file).
  /usr/bin/python3 harness/report.py figure OUT --kind line|profile|ranking|heatmap|grid
          [--x POINTER] [--y POINTER] [--metric M] [--methods a,b,c|all]
          [--variant ID] [--scene S] [--style paper|screen] [--columns 1|2]
          -o FILE.(pdf|svg|png)
      redraws one figure from OUT/report.json, without rendering:
        line     a metric (--metric: combined_relative_error, the default,
                 profile.rmse_terminator, view.rmse_grazing,
                 profile.position_error_deg or image.rmse) against the
                 levels of one axis (--x: its pointer or name; default the
                 first), a line per method with 95 % interval bars;
        profile  a variant's terminator profiles (--variant; default the
                 first);
        ranking  the primary metric (or --metric) per method with its
                 interval, in rank-group order;
        heatmap  a comparison metric over two axes (--x, --y; default the
                 study's first plot), one panel per method, one scene
                 (--scene) or all pooled;
        grid     a variant's images and difference images (--variant),
                 ground truth and methods side by side (--methods all: in
                 bands of 7 columns).
      --methods: a subset, in the order given (default: `none`, the
      methods report.json's figures.methods names, the best rank group's
      leader overall and per level, then the next best: at most 5;
      penumbra_stats.highlighted). --style paper: 8-pt text, exactly 3.5
      in (--columns 1) or 7 in (2, the default) wide, TrueType fonts in
      the PDF; screen: the report's look.
  /usr/bin/python3 harness/report.py figure OUT --kind
          achievable-share|achievable-contour [--style paper|screen]
          [--columns 1|2] -o FILE.(pdf|svg|png)
      draws from OUT/fit/fit.json (penumbra fit's; docs/achievable.md), not
      report.json: each method's share of the achievable improvement with
      its interval, or the contour plot of the floor's G* beside the
      methods and their differences from it (fit.json's `pictures`).
  /usr/bin/python3 harness/report.py table OUT --format latex|markdown|csv
          [--by POINTER] [--metric M] [-o FILE]
      the ranking table (rank group, method, combined error C with its
      interval, C minus the group leader's, terminator error removed,
      grazing-view difference, verdict), or with --by the per-level table
      (methods x the axis' levels, each cell mean [interval] (rank group
      in that level); CSV in long form); to stdout without -o. LaTeX:
      booktabs, every string escaped.
  /usr/bin/python3 harness/report.py contour CONTOUR.json OUTDIR
      writes OUTDIR/contour-<method>.*, contour-diff-<a>-<b>.* for every
      pair of methods in the given order, and the combined contour.*.

Prints every written file, one a line. Exit status 0 ok; 2 bad input
(missing file, malformed JSON, wrong format or version, a path outside OUT,
a bad option), one line on stderr: "report.py: <file or option>: <what>",
and nothing written; 1 an output error.
Nothing from the JSON is executed; every string from it is HTML-escaped
(by the template's autoescape).
The same input gives the same bytes (no dates or versions in the files).

report.json ("format": "penumbra-report", "version": 1; any number may be
null): penumbra, study{name,file}, units{}, axes[{pointer,label,values}],
renderers[{id,version,methods[],note}], variants[{id,scene,label,
axis_values[], renders[{renderer,representation,method,image,difference,
flip_map,profile{bin_degrees,value[],count[]}}]}], comparisons[{variant,scene,
renderer,method,reference,profile{rmse_terminator,...},image{rmse,ssim,...}}],
ranking{metric,reference,renderer,per_scene[{scene,methods[{method,mean,
count}]}],overall[...]}, missing[{renderer,method,why}],
failures[{render,error}], plots[{metric,x,y,kind,renderer}], lowpoly (null,
or the low-poly section: axes[], convergence_axis (an axes pointer or null),
renderers[{id,offsets[]}], missing[{renderer,offset or scene,why}],
variants[{id,scene,label,axis_values[],renders[{renderer,offset ("analytic":
the untessellated truth),triangles,image,difference,flip_map,exr,profile{}}]}],
comparisons[{variant,scene,axis_values[],renderer,offset,reference
("<renderer>:analytic"),shadow{darkened_fraction,max_darkening,
lost_shadow_fraction,shadow_shift_px,shadowed_pixels,...},profile{},
image{}}], ranking{metric,reference,renderer,per_scene[{scene,offsets[{offset,
darkened_fraction,darkened_fraction_ci,rmse_terminator,count,versus_best{pairs,
mean_difference,ci,tie}}]}],overall[...]}, units{}),
filtering (null, or [{map,run,source,json,csv,findings[]}]: each json a
filtering.json, see below), interplay (null, or {scene,map{file,size,digest},
filter,levels[],methods[],compared_against,truth,truth_check{},units,
rows[{level,method,rmse_terminator,rmse_terminator_ci,rmse_overall,
position_error_deg,image}],findings[]}). image, difference, json and csv are
paths relative to OUT.
Read when present (issue 37; older files fall back, penumbra_stats.py):
provenance{penumbra,commit,dirty,date,machine{},renderers{},study_sha256}
and notices[] (shown on the page only; no figure depends on them),
axes[].value_ids[], figures{methods[]} (the methods the profile, line and
grid figures show), statistics{primary_metric{id,name,unit}, rule,
headline[], notes[], by_axis[{pointer,label,numeric,levels[{value,
value_label,value_id,ranking}],interactions[{method,p,p_holm,depends,
levels[]}]}]} and, in every ranking's methods[], rank (the rank group),
group_leader, versus_leader{mean_difference,ci}, means{METRIC:{mean,ci}}.

The low-poly section (after the bump one) draws figures/lowpoly-convergence-
<group>.* (evaluator offsets vs evaluator:analytic over the convergence axis),
lowpoly-external-<group>.* (other renderers vs their own analytic render) and
lowpoly-shadow-<group>.* (cast-shadow loss and shift, scenes with a cast
shadow); a group is a scene plus the values of any other axes. The
filtering section (last) draws figures/filtering-<map>-<run>-<metric>.* per
entry (penumbra_filtering.py) and a table of its summary with intervals.

  /usr/bin/python3 harness/report.py filtering FILTERING.json OUTDIR
      writes OUTDIR/filtering-{profile_error,width_ratio,energy_ratio}.*
      (penumbra_filtering.py describes the input).

contour JSON ("format": "penumbra-contour", "version": 1): light_deg[],
deviation_deg[], methods[{id, G[deviation][light]}] (null: undefined).
"""

import os
import sys

# The C++ side runs this file from any working directory: its modules are
# the ones next to it. No __pycache__ in the source tree it runs from.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.dont_write_bytecode = True

from penumbra_achievable import (  # noqa: E402
    achievable_figures, load_study_fit)
from penumbra_commands import figure_command, table_command  # noqa: E402
from penumbra_contour import contour_figures, load_contour  # noqa: E402
from penumbra_data import BadInput, PageImages, Report  # noqa: E402
from penumbra_figures import report_figures  # noqa: E402
from penumbra_filtering import filtering_figures  # noqa: E402
from penumbra_html import write_report  # noqa: E402
from penumbra_plot import progress  # noqa: E402
from penumbra_stats import Stats  # noqa: E402


def run_report(out, self_contained=False):
    """Check OUT/report.json, draw its figures, write report.html; returns
    every path written, report.html last."""
    PageImages.embed, PageImages.out = self_contained, out
    report = Report(out)
    fit = load_study_fit(out)  # checked before anything is drawn
    figs = report_figures(report, Stats(report))
    figs['achievable'] = achievable_figures(
        fit, os.path.join(out, 'figures'))
    figs['written'] += figs['achievable']['written']
    progress('report.html' + (' (self-contained)' if self_contained else ''))
    return figs['written'] + [write_report(report, figs)]


def run_contour(path, outdir):
    return contour_figures(*load_contour(path), outdir)


USAGE = ('usage: report.py report OUT [--self-contained] | '
         'report.py figure OUT --kind line|profile|ranking|heatmap|grid|'
         'achievable-share|achievable-contour '
         '[options] '
         '-o FILE | report.py table OUT --format latex|markdown|csv '
         '[--by POINTER] [-o FILE] | '
         'report.py contour CONTOUR.json OUTDIR | '
         'report.py filtering FILTERING.json OUTDIR')


def main(argv):
    text = None
    try:
        if len(argv) in (2, 3) and argv[0] == 'report' and \
                argv[2:] in ([], ['--self-contained']):
            written = run_report(argv[1], len(argv) == 3)
        elif argv[:1] == ['figure']:
            written, _ = figure_command(argv[1:])
        elif argv[:1] == ['table']:
            written, text = table_command(argv[1:])
        elif len(argv) == 3 and argv[0] == 'contour':
            written = run_contour(argv[1], argv[2])
        elif len(argv) == 3 and argv[0] == 'filtering':
            written = filtering_figures(argv[1], argv[2])
        else:
            print(USAGE, file=sys.stderr)
            return 2
    except BadInput as e:
        print(f'report.py: {e}', file=sys.stderr)
        return 2
    except OSError as e:
        print(f'report.py: {e.filename or "output"}: {e.strerror or e}',
              file=sys.stderr)
        return 1
    if text is not None:
        sys.stdout.write(text)
    else:
        print('\n'.join(written))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
