"""Progress bars for long work (a sweep of runs, the time or load steps of one run), with a
time-left estimate (tqdm). Quiet where standard error is not a terminal (a log file, CI, a dask
worker) or with ``WORKBENCH_PROGRESS=0``; ``WORKBENCH_PROGRESS=1`` forces them on."""
from __future__ import annotations

import contextlib
import os
import sys


def enabled() -> bool:
    """Whether bars are drawn: ``WORKBENCH_PROGRESS`` (0/1) if set, else stderr is a terminal."""
    env = os.environ.get("WORKBENCH_PROGRESS")
    if env in ("0", "1"):
        return env == "1"
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class _Off:
    """A bar that draws nothing (the same calls as tqdm's)."""

    n = 0

    def update(self, n=1):
        self.n += n

    def set_postfix_str(self, *a, **k):
        pass

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def bar(total: int, desc: str, unit: str = "it", delay: float = 0.0, leave: bool = True):
    """A tqdm bar on stderr with elapsed time and time left, or a silent stand-in (module doc).
    ``delay`` (s): draw only once the work has lasted that long (short runs stay quiet)."""
    if not enabled():
        return _Off()
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, delay=delay, leave=leave, file=sys.stderr,
                dynamic_ncols=True, mininterval=0.5, smoothing=0.1)


@contextlib.contextmanager
def logging_through_bars():
    """Log lines printed above the bars instead of through them (while bars are drawn)."""
    if not enabled():
        yield
        return
    from tqdm.contrib.logging import logging_redirect_tqdm

    with logging_redirect_tqdm():
        yield
