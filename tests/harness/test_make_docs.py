#!/usr/bin/python3
"""docs/make_docs.py writes the generated pages of docs/ and --check names
each stale one.

In a copy of docs/: writing the pages makes --check pass; a generated page
edited by hand, a whole page removed and a section's end marker removed each
make --check fail (exit 1, or 2 for the broken page) naming that page, and
--check writes nothing. The real docs/ is checked by
Docs.GeneratedPagesMatchTheCode.

Usage: test_make_docs.py PENUMBRA SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True


def run(script, penumbra, docs, *extra):
    return subprocess.run(['/usr/bin/python3', script, '--penumbra', penumbra, *extra, docs],
                          capture_output=True, text=True, timeout=300)


def expect(condition, message):
    if not condition:
        print(f'FAIL: {message}', file=sys.stderr)
        sys.exit(1)


def snapshot(folder):
    out = {}
    for name in sorted(os.listdir(folder)):
        with open(os.path.join(folder, name), 'rb') as f:
            out[name] = f.read()
    return out


def main():
    penumbra, source = sys.argv[1], sys.argv[2]
    script = os.path.join(source, 'docs', 'make_docs.py')
    with tempfile.TemporaryDirectory() as tmp:
        docs = os.path.join(tmp, 'docs')
        shutil.copytree(os.path.join(source, 'docs'), docs,
                        ignore=shutil.ignore_patterns('__pycache__', '*.py'))
        done = run(script, penumbra, docs)
        expect(done.returncode == 0, f'writing the pages failed: {done.stderr}')
        done = run(script, penumbra, docs, '--check')
        expect(done.returncode == 0, f'--check after writing failed: {done.stderr}')
        for name in ('methods.md', 'renderers.md', 'csv-columns.md', 'report-json.md',
                     'exit-codes.md'):
            with open(os.path.join(docs, name), encoding='utf-8') as f:
                text = f.read()
            expect('_Generated ' in text and 'make_docs.py' in text,
                   f'{name} does not say it is generated and by which command')

        # A generated table edited by hand; a whole page removed.
        path = os.path.join(docs, 'methods.md')
        with open(path, encoding='utf-8') as f:
            text = f.read()
        head, row, tail = text.rpartition('| `chiang2019` |')  # the generated table's row
        expect(row and '<!-- BEGIN GENERATED methods' in head, 'no generated chiang2019 row')
        with open(path, 'w', encoding='utf-8') as f:
            f.write(head + '| `chiang2019-edited` |' + tail)
        os.remove(os.path.join(docs, 'csv-columns.md'))
        before = snapshot(docs)
        done = run(script, penumbra, docs, '--check')
        expect(done.returncode == 1, f'--check on stale pages exited {done.returncode}')
        expect('methods.md' in done.stderr and 'csv-columns.md' in done.stderr,
               f'--check does not name both stale pages: {done.stderr}')
        expect('renderers.md' not in done.stderr,
               f'--check names a current page: {done.stderr}')
        expect(snapshot(docs) == before, '--check wrote to docs/')

        # A hand-written page whose generated section lost its end marker.
        path = os.path.join(docs, 'renderers.md')
        with open(path, encoding='utf-8') as f:
            text = f.read()
        with open(path, 'w', encoding='utf-8') as f:
            f.write(text.replace('<!-- END GENERATED renderers -->', ''))
        done = run(script, penumbra, docs, '--check')
        expect(done.returncode == 2 and 'renderers.md' in done.stderr,
               f'a missing marker is not an error naming the page: {done.stderr}')
    print('make_docs: writes, checks and names stale pages')


if __name__ == '__main__':
    main()
