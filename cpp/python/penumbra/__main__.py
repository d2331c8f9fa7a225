"""``python3 -m penumbra ARGS``: the command line, run in this process, so
that user methods registered in Python (penumbra.method) are available.

``--methods-from FILE.py`` (repeatable, any command) runs FILE first, which
registers its methods; for ``run``, each method FILE registers is also
measured in the study (``--add-method ID``). The ``penumbra`` binary hands
``run --methods-from`` over to this module.
"""

import runpy
import sys

import penumbra


def _split(args):
    """(files, the other arguments) from --methods-from FILE / =FILE."""
    files, rest = [], []
    it = iter(args)
    for a in it:
        if a == "--methods-from":
            path = next(it, None)
            if path is None:
                sys.exit("penumbra: --methods-from: expected a Python file")
            files.append(path)
        elif a.startswith("--methods-from="):
            files.append(a.split("=", 1)[1])
        else:
            rest.append(a)
    return files, rest


def main(argv):
    files, rest = _split(argv)
    added = []
    for path in files:
        before = set(penumbra.user_methods())
        try:
            runpy.run_path(path, run_name="penumbra_methods")
        except OSError as e:
            print(f"penumbra: --methods-from {path}: {e.strerror or e}", file=sys.stderr)
            return 2
        added += sorted(set(penumbra.user_methods()) - before)
        if not added:
            print(f"penumbra: --methods-from {path}: the file registers no method "
                  "(decorate a function with @penumbra.method)", file=sys.stderr)
            return 2
    if rest and rest[0] == "run":
        for id in added:
            rest += ["--add-method", id]
    sys.stdout.flush()
    sys.stderr.flush()
    return penumbra._penumbra.cli_console([str(a) for a in rest])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
