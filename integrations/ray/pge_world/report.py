"""Reporting: progress (tiles done, rate, ETA) and ``--timings``, on stderr."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TextIO

from . import IMPORTED_AT
from .manifest import VARIANTS_BIN
from .records import VariantsEntry


class Progress:
    """Tiles done / total, rate and ETA: one line rewritten on a terminal, else one a tile."""

    def __init__(self, total: int, skipped: int, quiet: bool, stream: TextIO | None = None) -> None:
        """Count ``skipped`` of ``total`` tiles as done; print nothing when ``quiet``."""
        self.total = total
        self.done = skipped
        self.skipped = skipped
        self.quiet = quiet
        self.start = time.monotonic()
        self.stream = stream if stream is not None else sys.stderr
        self.tty = self.stream.isatty()
        self.note: str | None = None

    def later(self, line: str) -> None:
        """Say ``line`` with the first tile written (a run that fails says only its error)."""
        self.note = line

    def tile(self, i: int, j: int) -> None:
        """Count tile (i, j) as written."""
        self.done += 1
        if self.quiet:
            return
        if self.note is not None:
            self.stream.write(self.note + "\n")
            self.note = None
        grown = self.done - self.skipped
        elapsed = time.monotonic() - self.start
        rate = grown / elapsed if elapsed > 0 else 0.0
        left = self.total - self.done
        eta = f"{left / rate:.0f}s" if rate > 0 else "?"
        line = (
            f"tiles {self.done}/{self.total} (tile {i},{j}) "
            f"{rate:.2f} tiles/s, {elapsed:.0f}s elapsed, ETA {eta}"
        )
        if self.tty:
            self.stream.write("\r\033[K" + line + ("\n" if left == 0 else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def say(self, line: str) -> None:
        """Print ``line`` on a line of its own."""
        if not self.quiet:
            self.stream.write(line + "\n")
            self.stream.flush()


def variants_line(entry: VariantsEntry, waited: float) -> str:
    """Return what a run says of the shared variants it wrote."""
    return (
        f"variants: {entry['bytes'] / 1e6:.1f} MB in {VARIANTS_BIN}, written once "
        f"(waited {waited:.1f}s for them after connecting)"
    )


@dataclass(frozen=True)
class FinishedBatch:
    """A batch back from its task: its tiles, its node, when it started, its time there."""

    tiles: int
    node: str
    started: float
    seconds: float


class Clock:
    """When each phase of the run ended (``--timings``), in seconds since the process started.

    On Linux the start is the kernel's, so Python's start and imports count.
    """

    def __init__(self, on: bool, stream: TextIO | None = None) -> None:
        """Make a clock that reports only when ``on``."""
        self.on = on
        self.start = process_start()
        self.marks: list[tuple[str, float]] = []
        self.stream = stream if stream is not None else sys.stderr

    def mark(self, phase: str) -> None:
        """Note that ``phase`` has just ended."""
        self.marks.append((phase, time.time() - self.start))

    def report(self, batches: Sequence[FinishedBatch] = ()) -> None:
        """Print the phases and the batches' own times."""
        if not self.on:
            return
        lines = [f"  {t:6.2f}s  {phase}" for phase, t in self.marks]
        for b in batches:
            lines.append(
                f"  batch of {b.tiles} tiles on {b.node}: started at "
                f"{b.started - self.start:.2f}s, {b.seconds:.2f}s in the task"
            )
        self.stream.write("timings (seconds since the process started):\n")
        self.stream.write("\n".join(lines) + "\n")


def process_start() -> float:
    """Return this process's start as a Unix time: from /proc on Linux, else the package's import.

    The age comes from the system's uptime (hundredths of a second), not from /proc/stat's
    boot time, which is rounded to the second and put the start up to a second early.
    """
    try:
        with open("/proc/self/stat", encoding="ascii") as f:
            ticks = int(f.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/uptime", encoding="ascii") as f:
            uptime = float(f.read().split()[0])
        age = uptime - ticks / os.sysconf("SC_CLK_TCK")
        return time.time() - max(age, 0.0)
    except (OSError, ValueError, IndexError):
        return IMPORTED_AT
