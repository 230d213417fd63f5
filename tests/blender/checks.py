"""What the Blender tests share: their arguments after Blender's `--`, the recipes on sys.path, checks.

Each tests/blender/NAME.py is run as `blender -b -P tests/blender/NAME.py -- REPO ARGS...` by
tests/cli/blender-NAME.sh; REPO is the repository's root, whose docs/examples/blender/ holds the
recipes under test.
"""
import os
import sys

ARGS = sys.argv[sys.argv.index("--") + 1:]
ROOT = ARGS[0]
sys.path.insert(0, os.path.join(ROOT, "docs", "examples", "blender"))

failures = 0


def check(what, cond, detail=""):
    """Prints `ok` or `FAIL` and the line; counts the failures."""
    global failures
    print(("ok    " if cond else "FAIL  ") + what + (": " + detail if detail else ""))
    failures += 0 if cond else 1


def finish():
    """Ends Blender with status 1 when a check failed."""
    print("%d failed" % failures)
    sys.exit(1 if failures else 0)
