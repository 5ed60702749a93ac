"""The ``paraspace`` command line run in this process, read like a finished subprocess.

``run_cli(*args)`` is ``paraspace.app.cli.main(list(args))`` with stdout and stderr captured and
argparse's exits (``SystemExit``) turned into the return code: the same parser, commands, messages
and exit codes as ``python -m paraspace.app.cli ...``, without starting an interpreter and reloading
every numba kernel from the on-disk cache for each call (1-3 s of CPU each on the 2-core machine).
An exception the command does not handle propagates (a subprocess would print a traceback): the
test fails either way. The entry point itself, as a real process, stays tested by
tests/test_cli.py::test_workspace_json_contract and tests/test_packaging.py (``python -m paraspace``).
"""

from __future__ import annotations

import contextlib
import io
import subprocess

from paraspace.app.cli import main


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    """``paraspace ARGS...`` in-process: returncode, stdout and stderr as ``subprocess.run`` gives them."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(list(args))
        except SystemExit as exc:  # argparse's usage errors and --help/--version
            if exc.code is None:
                rc = 0
            elif isinstance(exc.code, int):
                rc = exc.code
            else:
                err.write(f"{exc.code}\n")
                rc = 1
    return subprocess.CompletedProcess(["paraspace", *args], rc, out.getvalue(), err.getvalue())
