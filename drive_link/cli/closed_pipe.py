"""A closed output pipe ends a console script quietly, as it ends other Unix tools.

``drive-link objects | head -1``: once ``head`` has its line it closes the pipe and the next
write raises :class:`BrokenPipeError`. :func:`run_quietly` (around a console script's main)
takes that as the end: nothing more can be said, so no traceback and no error line; the exit
status is 141 (128 + SIGPIPE, what a shell reports for ``yes | head -1``'s ``yes``). It exits
normally (``finally`` blocks, ``atexit`` and child processes' shutdown still run), with stdout
and stderr pointed at ``/dev/null`` so that Python's own flush at exit has nowhere to fail.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable

__all__ = ["EXIT_CLOSED_PIPE", "run_quietly", "silence_output"]

#: Exit status after the reader closed the output pipe (128 + SIGPIPE).
EXIT_CLOSED_PIPE = 141


def silence_output() -> None:
    """Point stdout and stderr at /dev/null (the reader of the pipe is gone)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        return
    for stream in (sys.stdout, sys.stderr):
        try:
            os.dup2(devnull, stream.fileno())
        except (OSError, ValueError, AttributeError):
            pass
    os.close(devnull)


def run_quietly(main: Callable[[], int]) -> int:
    """``main()``'s exit status, its output flushed; :data:`EXIT_CLOSED_PIPE`, silently, when
    the reader of stdout (or stderr) closed the pipe."""
    try:
        rc = main()
        sys.stdout.flush()
        sys.stderr.flush()
        return rc
    except BrokenPipeError:
        silence_output()
        return EXIT_CLOSED_PIPE
