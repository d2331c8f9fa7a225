#!/usr/bin/python3
"""Writes the pages of docs/ whose content the code holds, from the code.

    python3 docs/make_docs.py --penumbra build/penumbra [docs]          # write
    python3 docs/make_docs.py --penumbra build/penumbra --check [docs]  # compare
    python3 docs/make_docs.py --penumbra build/penumbra --performance [docs]

Sources, one per generated page or marked section:
  docs/methods.md     section "methods"    `penumbra methods --json`
  docs/renderers.md   section "renderers"  `penumbra renderers --json`
  docs/exit-codes.md  whole page           `penumbra exit-codes --json` (a marked
                                           fallback table below while the
                                           binary has no such command)
  docs/csv-columns.md whole page           harness/csv-columns.json
  docs/report-json.md whole page           harness/report.schema.json
  docs/performance.md section "performance" `penumbra bench` and the CPU model,
                                           only with --performance; never checked
                                           (its numbers belong to one machine)

A whole page's first line says that it is generated and by which command; a
section lies between `<!-- BEGIN GENERATED NAME ... -->` and
`<!-- END GENERATED NAME -->` in a hand-written page. --check writes nothing
and exits 1 naming each stale page. Debian's python3, standard library only.
"""

import argparse
import json
import os
import platform
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
COMMAND = 'python3 docs/make_docs.py --penumbra build/penumbra docs'
PERFORMANCE_COMMAND = 'python3 docs/make_docs.py --penumbra build/penumbra --performance docs'

# FALLBACK, used only while `penumbra exit-codes` does not exist in the binary
# given: the exit statuses of cpp/cli/cli.h (kExitOk, kExitFailure,
# kExitBadInput, kExitThreshold) and the signal statuses of commands.cpp
# (StopSignals). Delete it once every build has the command.
FALLBACK_EXIT_CODES = [
    {'code': 0, 'name': 'ok', 'meaning': 'success'},
    {'code': 1, 'name': 'failure',
     'meaning': 'a run failed: an external renderer missing, failing, timing out or returning an '
                'image of the wrong size or with NaN/Inf values, or an internal error'},
    {'code': 2, 'name': 'bad-input',
     'meaning': 'bad input: usage, an unreadable or invalid scene or study, an unwritable output '
                'or one with the wrong extension, a render estimated above --max-memory, a scene '
                'the chosen renderer cannot express'},
    {'code': 3, 'name': 'threshold',
     'meaning': 'a comparison missed its bound (calibrate, compare --max-profile-rmse) or an '
                'image holds NaN or Inf values'},
    {'code': 129, 'name': 'sighup', 'meaning': 'stopped by SIGHUP (128 + 1)'},
    {'code': 130, 'name': 'sigint', 'meaning': 'stopped by SIGINT, Ctrl-C (128 + 2)'},
    {'code': 143, 'name': 'sigterm', 'meaning': 'stopped by SIGTERM (128 + 15)'},
]


class DocsError(Exception):
    pass


def cell(text):
    """Text safe inside a Markdown table cell."""
    text = '' if text is None else str(text)
    # Backslashes and stars only outside `code spans`; pipes everywhere (GFM
    # tables split on them even inside code spans).
    parts = text.split('`')
    for i in range(0, len(parts), 2):
        parts[i] = parts[i].replace('\\', '\\\\').replace('*', '\\*')
    text = '`'.join(parts).replace('|', '\\|')
    # Only a '<' that would open an HTML tag (<Ns> would; <Ng,wi> and <= do not).
    text = re.sub(r'<(?=/?[A-Za-z][A-Za-z0-9-]*(\s|/?>))', '&lt;', text)
    return ' '.join(text.split())


def sentence(text):
    text = text.strip()
    return text if not text or text[-1] in '.!?' else text + '.'


def code(text):
    return '`' + str(text) + '`'


def number(value):
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return format(value, '.6g') if isinstance(value, float) else str(value)


def table(header, rows):
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    lines += ['| ' + ' | '.join(row) + ' |' for row in rows]
    return lines


def run_json(penumbra, *args):
    try:
        done = subprocess.run([penumbra, *args], capture_output=True, text=True, timeout=120)
    except OSError as e:
        raise DocsError(f'cannot run {penumbra}: {e}')
    if done.returncode != 0:
        raise DocsError(f'`penumbra {" ".join(args)}` exited {done.returncode}: '
                        f'{done.stderr.strip()[:500]}')
    try:
        return json.loads(done.stdout)
    except ValueError as e:
        raise DocsError(f'`penumbra {" ".join(args)}` printed no JSON: {e}')


def has_command(penumbra, name):
    done = subprocess.run([penumbra, '--help'], capture_output=True, text=True, timeout=60)
    return any(line.split()[:1] == [name] for line in done.stdout.splitlines()
               if line.startswith('  '))


def parameters_text(parameters):
    parts = []
    for p in parameters or []:
        parts.append(f'{code(p["name"])} in [{number(p["min"])}, {number(p["max"])}] '
                     f'({p["unit"]}), default {number(p["default"])}: {p["description"]}')
    return '; '.join(parts)


# ---------------------------------------------------------------- methods


def methods_section(methods):
    by_kind = {}
    for m in methods:
        by_kind.setdefault(m['kind'], []).append(m)
    known = {'terminator', 'normal_adjustment', 'offset', 'roughness_filter'}
    unknown = sorted(set(by_kind) - known)
    if unknown:
        raise DocsError(f'`penumbra methods --json` has kinds this generator does not know: '
                        f'{", ".join(unknown)}')
    out = [f'_Generated from `penumbra methods --json` by `{COMMAND}`; do not edit this '
           f'section by hand._', '']
    terminator = by_kind.get('terminator', [])
    out += ['### Terminator methods', '',
            f'{len(terminator)} methods: what `/terminator/method`, `--method` and a study\'s `methods` take. '
            '*Family*: factor, factor+adjustment, adjustment or microfacet. *Lobes*: what a '
            'factor scales (`scene`: `/terminator/lobes`). *Reference*: the factor\'s '
            'reference normal (`scene`: `/terminator/reference_normal`). *Identity*: the plain '
            'BSDF where `Ns == Ng`.', '']
    rows = []
    for m in terminator:
        notes = [sentence(m['summary'])]
        if m.get('parameters'):
            notes.append('Parameters: ' + parameters_text(m['parameters']) + '.')
        if m.get('note'):
            notes.append('Note: ' + sentence(m['note']))
        family = m['family']
        if m.get('normal_adjustment', 'none') != 'none':
            family += f' ({m["normal_adjustment"]})'
        rows.append([code(m['id']), cell(family), cell(m['factor_lobes']),
                     cell(m['reference_normal']),
                     'yes' if m['identity_without_deviation'] else 'no',
                     cell(' '.join(notes)), cell(m['source'])])
    out += table(['id', 'family', 'lobes', 'reference', 'identity', 'what it does', 'source'],
                 rows)
    adjustments = by_kind.get('normal_adjustment', [])
    out += ['', '### Normal adjustments', '',
            f'{len(adjustments)} adjustments: what `/terminator/normal_adjustment` takes (a method may bring its own). '
            '*Diffuse*: whether the adjustment also changes the diffuse lobe\'s normal.', '']
    out += table(['id', 'diffuse', 'what it does', 'source'],
                 [[code(a['id']), 'yes' if a.get('touches_diffuse') else 'no',
                   cell(a['summary']), cell(a['source'])] for a in adjustments])
    offsets = by_kind.get('offset', [])
    out += ['', '### Shadow-ray offsets', '',
            f'{len(offsets)} offsets: what `/offset/method` and `--offset` take (low-poly meshes).', '']
    out += table(['id', 'parameters', 'what it does', 'source'],
                 [[code(o['id']), cell(parameters_text(o.get('parameters'))),
                   cell(o['summary']), cell(o['source'])] for o in offsets])
    filters = by_kind.get('roughness_filter', [])
    out += ['', '### Roughness filters', '',
            f'{len(filters)} filters: what `/height/filter/method`, `penumbra filtering --filter` and a filtering '
            'section\'s `filters` take; the lobe is a slope-space `alpha^2` tensor on the '
            'named distribution.', '']
    out += table(['id', 'distribution', 'input', 'parameters', 'what it does', 'source'],
                 [[code(f['id']), cell(f['distribution']), cell(f['input']),
                   cell(parameters_text(f.get('parameters'))), cell(f['summary']),
                   cell(f['source'])] for f in filters])
    return out


# -------------------------------------------------------------- renderers


def renderers_section(renderers):
    out = [f'_Generated from `penumbra renderers --json` by `{COMMAND}`; do not edit this '
           f'section by hand._', '']
    rows = []
    for r in renderers:
        package = code(r['debian_package']) if r['debian_package'] else '(built in)'
        executable = (f'{code(r["executable"])} or {code("$" + r["executable_variable"])}'
                      if r['executable'] else '-')
        flags = [name for name in ('height_maps', 'normal_maps', 'plane', 'props',
                                   'consistent_normals', 'mesh_bump') if r.get(name)]
        rows.append([code(r['id']), cell(r['name']), package, executable,
                     str(len(r['bump_methods'])), str(len(r['offsets'])),
                     cell(', '.join(f.replace('_', ' ') for f in flags))])
    out += table(['id', 'name', 'Debian package', 'executable', 'bump methods', 'offsets',
                  'also renders'], rows)
    for r in renderers:
        out += ['', f'### `{r["id"]}`: {cell(r["name"])}', '', cell(r['note']) + '.', '']
        lines = [
            ('bump methods', ', '.join(code(m) for m in r['bump_methods'])),
            ('smooth and displacement methods',
             ', '.join(code(m) for m in r['smooth_and_displacement_methods'])),
            ('shadow-ray offsets', ', '.join(code(o) for o in r['offsets'])),
        ]
        for key, label in (('methods_why_not', 'why not more methods'),
                           ('offsets_why_not', 'why not more offsets')):
            if r.get(key):
                lines.append((label, cell(r[key])))
        for key, label in (('height_maps', 'image height maps'), ('normal_maps', 'normal maps'),
                           ('plane', 'the plane'),
                           ('consistent_normals', 'consistent normal interpolation'),
                           ('mesh_bump', 'bump on a mesh shape')):
            why = r.get(key + '_why_not', '')
            lines.append((label, 'yes' if r.get(key) else 'no' + (f': {cell(why)}' if why else '')))
        lines.append(('props (extra spheres)', 'yes' if r.get('props') else 'no'))
        if r.get('reference_ni_methods'):
            lines.append(('reference normal Ni whatever the scene says (on a mesh under Ng: '
                          'refused)', ', '.join(code(m) for m in r['reference_ni_methods'])))
        out += [f'- {label}: {text}' for label, text in lines]
    return out


# ------------------------------------------------------------- exit codes


def exit_codes_page(penumbra):
    if has_command(penumbra, 'exit-codes'):
        codes = run_json(penumbra, 'exit-codes', '--json')
        source = '`penumbra exit-codes --json`'
    else:
        codes = FALLBACK_EXIT_CODES
        source = ('the fallback table in docs/make_docs.py (this build has no '
                  '`penumbra exit-codes`)')
    if not isinstance(codes, list) or not all(
            isinstance(c, dict) and isinstance(c.get('code'), int) and 'name' in c and
            'meaning' in c for c in codes):
        raise DocsError('`penumbra exit-codes --json`: expected an array of objects with '
                        '"code" (integer), "name" and "meaning"')
    out = [f'_Generated from {source} by `{COMMAND}`; do not edit by hand._', '',
           '# Exit status', '',
           'Every `penumbra` command ends with one of these statuses. Bad input (2) is kept '
           'apart from a missed bound (3), unlike OpenImageIO\'s `idiff`, so that scripts can '
           'tell the two apart. A command stopped by a signal ends its running renderers and '
           'leaves nothing half-written; a study resumes where it stopped. See '
           '[command-line.md](command-line.md) for the error lines.', '']
    out += table(['status', 'name', 'meaning'],
                 [[str(c['code']), code(c['name']), cell(c['meaning'])] for c in codes])
    return out


# ------------------------------------------------------------ CSV columns


def csv_columns_page(doc):
    out = [f'_Generated from `harness/csv-columns.json` by `{COMMAND}`; do not edit by '
           f'hand._', '', '# CSV columns', '', cell(doc['description']), '',
           'How to read the files, with examples: [report.md](report.md).', '',
           '## Conventions', '']
    out += [f'- **{cell(k)}**: {cell(v)}' for k, v in doc['conventions'].items()]
    out += ['', '## Axis columns', '']
    out += [f'- **{cell(k)}**: {cell(v)}' for k, v in doc['axis_columns'].items()]
    for name, spec in doc['files'].items():
        out += ['', f'## {name}', '', f'Rows: {cell(spec["rows"])}.', '']
        rows = []
        for c in spec['columns']:
            if 'axes' in c:
                rows.append(['*(axes)*', '', '', cell(c['axes'])])
                continue
            text = c['description']
            if c.get('empty'):
                text += f'; empty {c["empty"]}'
            rows.append([code(c['name']), cell(c['type']), cell(c.get('unit') or ''), cell(text)])
        out += table(['column', 'type', 'unit', 'meaning'], rows)
    return out


# ----------------------------------------------------------- report.json


def schema_type(node):
    if '$ref' in node:
        name = node['$ref'].rsplit('/', 1)[-1]
        return f'[{name}](#{name})'
    if 'const' in node:
        return 'const ' + code(json.dumps(node['const']))
    if 'enum' in node:
        return 'one of ' + ', '.join(code(json.dumps(v)) for v in node['enum'])
    if 'anyOf' in node:
        return ' or '.join(schema_type(n) for n in node['anyOf'])
    kind = node.get('type', '')
    kind = ' or '.join(kind) if isinstance(kind, list) else kind
    if kind == 'array' and 'prefixItems' in node:
        kind = 'array [' + ', '.join(schema_type(n) for n in node['prefixItems']) + ']'
    elif kind == 'array' and isinstance(node.get('items'), dict) and '$ref' in node['items']:
        kind = 'array of ' + schema_type(node['items'])
    elif (kind == 'object' and isinstance(node.get('additionalProperties'), dict) and
          '$ref' in node['additionalProperties']):
        kind = 'object of ' + schema_type(node['additionalProperties'])
    limits = []
    if 'minimum' in node:
        limits.append(f'>= {number(node["minimum"])}')
    if 'minItems' in node:
        limits.append(f'at least {node["minItems"]} items')
    if 'maxItems' in node:
        limits.append(f'at most {node["maxItems"]} items')
    if 'pattern' in node:
        limits.append(f'matching {code(node["pattern"])}')
    return kind + (' (' + ', '.join(limits) + ')' if limits else '')


def table_type(node):
    return schema_type(node).replace('|', '\\|')  # a pattern's '|' would split the cell


def schema_rows(node, pointer, rows):
    """One row per key under `node` (inline objects and arrays recursed; a
    $ref is a link to its own section)."""
    for key, child in node.get('properties', {}).items():
        path = f'{pointer}/{key}'
        required = key in node.get('required', [])
        rows.append([code(path), table_type(child), 'yes' if required else '',
                     cell(child.get('description', ''))])
        schema_children(child, path, rows)


def schema_children(child, path, rows):
    if '$ref' in child:
        return
    if 'properties' in child:
        schema_rows(child, path, rows)
    items = child.get('items')
    if isinstance(items, dict) and '$ref' not in items and (
            'properties' in items or 'items' in items):
        rows.append([code(path + '/*'), table_type(items), '',
                     cell(items.get('description', ''))])
        schema_children(items, path + '/*', rows)
    extra = child.get('additionalProperties')
    if isinstance(extra, dict) and '$ref' not in extra and (
            'properties' in extra or 'items' in extra or 'additionalProperties' in extra):
        rows.append([code(path + '/KEY'), table_type(extra), '',
                     cell(extra.get('description', ''))])
        schema_children(extra, path + '/KEY', rows)


def report_json_page(schema):
    out = [f'_Generated from `harness/report.schema.json` by `{COMMAND}`; do not edit by '
           f'hand._', '', '# report.json', '', cell(schema['title']) + '.', '',
           cell(schema['description']), '',
           'Pointers use `*` for every element of an array and `KEY` for every key of an '
           'object map; a linked type is described in its own section below. Undocumented '
           'keys are refused by the schema (`additionalProperties: false`), so a new key needs '
           'its entry in `harness/report.schema.json`. How to read the report: '
           '[report.md](report.md).', '', '## Top level', '']
    rows = []
    schema_rows(schema, '', rows)
    out += table(['pointer', 'type', 'required', 'meaning'], rows)
    for name, node in schema.get('$defs', {}).items():
        out += ['', f'## {name}', '', f'Type: {schema_type(node)}.']
        if node.get('description'):
            out += ['', cell(node['description'])]
        rows = []
        schema_rows(node, '', rows)
        schema_children({k: v for k, v in node.items() if k != 'properties'}, '', rows)
        if rows:
            out += [''] + table(['key', 'type', 'required', 'meaning'], rows)
    return out


# ------------------------------------------------------------ performance


def cpu_model():
    try:
        with open('/proc/cpuinfo', encoding='utf-8') as f:
            for line in f:
                if line.startswith('model name'):
                    return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or 'unknown CPU'


def load_note(load, cores):
    """What the one-minute load average before the bench says about its numbers."""
    if load > cores:
        return 'above the core count: other work shared the cores and the numbers are low'
    if load > 0.25 * cores:
        return 'other work was running: the numbers may be low'
    return 'an idle machine'


def performance_section(penumbra):
    version = subprocess.run([penumbra, '--version'], capture_output=True, text=True).stdout
    commit = subprocess.run(['git', '-C', ROOT, 'rev-parse', '--short=12', 'HEAD'],
                            capture_output=True, text=True).stdout.strip()
    load = os.getloadavg()[0]
    bench = subprocess.run([penumbra, 'bench'], capture_output=True, text=True)
    if bench.returncode != 0:
        raise DocsError(f'`penumbra bench` exited {bench.returncode}: {bench.stderr.strip()}')
    return [f'_Generated by `{PERFORMANCE_COMMAND}`, which runs `penumbra bench`; not part '
            f'of `--check` (the numbers belong to one machine)._', '',
            f'- CPU: {cell(cpu_model())}, {os.cpu_count()} logical cores; load average '
            f'{load:.1f} when the run started ({load_note(load, os.cpu_count() or 1)})',
            f'- Penumbra: {cell(version.strip() or "unknown version")}, commit '
            f'{code(commit or "not from a git checkout")}',
            '- command: `penumbra bench` (defaults: 512x512, 16 spp)', '',
            '```', *bench.stdout.rstrip('\n').splitlines(), '```']


# ------------------------------------------------------------- the pages


def whole(lines):
    return '\n'.join(lines) + '\n'


def replace_section(text, name, lines, page):
    begin = re.compile(r'^<!-- BEGIN GENERATED ' + re.escape(name) + r'\b.*-->$', re.M)
    end = re.compile(r'^<!-- END GENERATED ' + re.escape(name) + r' -->$', re.M)
    b, e = begin.search(text), end.search(text)
    if not b or not e or e.start() < b.end():
        raise DocsError(f'{page}: no "<!-- BEGIN GENERATED {name} ... -->" and '
                        f'"<!-- END GENERATED {name} -->" lines to write the section between')
    return text[:b.end()] + '\n' + '\n'.join(lines) + '\n' + text[e.start():]


def generated(penumbra):
    """(page, section name or None, lines) for every checked page."""
    with open(os.path.join(ROOT, 'harness', 'csv-columns.json'), encoding='utf-8') as f:
        columns = json.load(f)
    with open(os.path.join(ROOT, 'harness', 'report.schema.json'), encoding='utf-8') as f:
        schema = json.load(f)
    return [
        ('methods.md', 'methods', methods_section(run_json(penumbra, 'methods', '--json'))),
        ('renderers.md', 'renderers',
         renderers_section(run_json(penumbra, 'renderers', '--json'))),
        ('exit-codes.md', None, exit_codes_page(penumbra)),
        ('csv-columns.md', None, csv_columns_page(columns)),
        ('report-json.md', None, report_json_page(schema)),
    ]


def read(path):
    try:
        with open(path, encoding='utf-8') as f:
            return f.read()
    except FileNotFoundError:
        return None


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--penumbra', required=True, help='the penumbra binary')
    parser.add_argument('--check', action='store_true',
                        help='write nothing; exit 1 naming each stale page')
    parser.add_argument('--performance', action='store_true',
                        help='only run `penumbra bench` into docs/performance.md')
    parser.add_argument('docs', nargs='?', default=HERE, help='the docs folder')
    args = parser.parse_args(argv)
    try:
        if args.performance:
            targets = [('performance.md', 'performance', performance_section(args.penumbra))]
        else:
            targets = generated(args.penumbra)
        stale = []
        for page, section, lines in targets:
            path = os.path.join(args.docs, page)
            old = read(path)
            if section is None:
                new = whole(lines)
            elif old is None:
                raise DocsError(f'{path}: missing (a hand-written page with a generated '
                                f'section "{section}")')
            else:
                new = replace_section(old, section, lines, path)
            if new == old:
                continue
            if args.check:
                stale.append(path + (f' (section "{section}")' if section else ''))
            else:
                with open(path, 'w', encoding='utf-8') as f:
                    f.write(new)
                print(f'wrote {path}')
        if stale:
            for path in stale:
                print(f'stale: {path}', file=sys.stderr)
            print(f'make_docs: {len(stale)} generated page(s) differ from the code; '
                  f'run `{COMMAND}` and commit the result', file=sys.stderr)
            return 1
    except DocsError as e:
        print(f'make_docs: error: {e}', file=sys.stderr)
        return 2
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
