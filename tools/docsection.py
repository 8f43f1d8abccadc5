"""Lets a measuring tool regenerate its report in docs/: `--doc FILE` (taken off the
command line before the tool's own arguments are read) copies what the tool prints on
standard output into FILE, between the lines `<!-- BEGIN NAME -->` and
`<!-- END NAME -->`, replacing what was there. The file is written to a temporary name
and renamed, so an interrupted run leaves the old report.

    python3 tools/real_scenes.py --doc docs/real-scenes.md
"""

import io
import os
import sys


def replace(path, name, text):
    """Puts `text` between NAME's markers in `path` (which must hold them)."""
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    with open(path, encoding="utf-8") as f:
        doc = f.read()
    if begin not in doc or end not in doc:
        sys.exit(f"{path}: error: no section {begin} ... {end} to write the report into")
    head, rest = doc.split(begin, 1)
    _, tail = rest.split(end, 1)
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(f"{head}{begin}\n{text.rstrip()}\n{end}{tail}")
    os.replace(tmp, path)


class _Tee(io.TextIOBase):
    def __init__(self, out):
        self.out, self.kept = out, io.StringIO()

    def write(self, s):
        self.kept.write(s)
        return self.out.write(s)

    def flush(self):
        self.out.flush()


def run(main, name):
    """Runs `main()`; with `--doc FILE` on the command line, also writes its standard
    output into FILE's section NAME. Returns main's result."""
    path = None
    if "--doc" in sys.argv:
        i = sys.argv.index("--doc")
        if i + 1 >= len(sys.argv):
            sys.exit("--doc: error: it needs a file (a docs/*.md with the section's markers)")
        path = sys.argv[i + 1]
        del sys.argv[i:i + 2]
        try:  # fails now, not after the measuring
            with open(path, encoding="utf-8") as f:
                doc = f.read()
        except OSError as e:
            sys.exit(f"{path}: error: cannot read: {e.strerror}")
        if f"<!-- BEGIN {name} -->" not in doc:
            sys.exit(f"{path}: error: no section <!-- BEGIN {name} --> to write the report into")
    tee = _Tee(sys.stdout)
    sys.stdout = tee
    try:
        result = main()
    finally:
        sys.stdout = tee.out
    if path:
        replace(path, name, tee.kept.getvalue())
    return result
