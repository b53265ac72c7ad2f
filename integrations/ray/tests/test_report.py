"""What a run says on stderr: progress, the variants' line, ``--timings``."""

from __future__ import annotations

import io
import re

import pytest

from pge_world.records import VariantsEntry
from pge_world.report import Clock, FinishedBatch, Progress, variants_line

pytestmark = pytest.mark.unit

LINE = r"tiles {done}/{total} \(tile {i},{j}\) [0-9.]+ tiles/s, [0-9]+s elapsed, ETA ([0-9]+s|\?)"


def test_progress_counts_the_skipped_tiles_and_says_the_note_first() -> None:
    out = io.StringIO()
    progress = Progress(4, 1, False, out)
    progress.say("1 of 4 tiles already in DIR: skipped")
    progress.later("variants: written once")
    progress.tile(0, 1)
    progress.tile(2, 3)
    lines = out.getvalue().splitlines()
    assert lines[:2] == ["1 of 4 tiles already in DIR: skipped", "variants: written once"]
    assert re.fullmatch(LINE.format(done=2, total=4, i=0, j=1), lines[2]), lines[2]
    assert re.fullmatch(LINE.format(done=3, total=4, i=2, j=3), lines[3]), lines[3]
    assert len(lines) == 4 and progress.done == 3 and progress.note is None


def test_quiet_progress_says_nothing_but_counts() -> None:
    out = io.StringIO()
    progress = Progress(2, 0, True, out)
    progress.later("a note")
    progress.tile(0, 0)
    progress.say("a line")
    assert out.getvalue() == "" and progress.done == 1


def test_the_variants_line_gives_their_size_and_the_wait() -> None:
    entry: VariantsEntry = {
        "file": "variants.bin",
        "sha256": "0" * 64,
        "bytes": 26_600_000,
        "description": "variants.json",
        "descriptionSha256": "1" * 64,
        "descriptionBytes": 2_200_000,
    }
    assert variants_line(entry, 1.0) == (
        "variants: 26.6 MB in variants.bin, written once (waited 1.0s for them after connecting)"
    )


def test_timings_list_the_phases_and_the_batches_only_when_asked() -> None:
    silent = io.StringIO()
    off = Clock(False, silent)
    off.mark("phase")
    off.report()
    assert silent.getvalue() == ""

    out = io.StringIO()
    clock = Clock(True, out)
    clock.mark("Python started, manifest read")
    clock.mark("pge tiles")
    batch = FinishedBatch(tiles=8, node="host-a", started=clock.start + 1.5, seconds=0.25)
    clock.report([batch])
    lines = out.getvalue().splitlines()
    assert lines[0] == "timings (seconds since the process started):"
    assert re.fullmatch(r"  +[0-9]+\.[0-9]{2}s  Python started, manifest read", lines[1])
    assert re.fullmatch(r"  +[0-9]+\.[0-9]{2}s  pge tiles", lines[2])
    assert lines[3] == "  batch of 8 tiles on host-a: started at 1.50s, 0.25s in the task"
    assert len(lines) == 4
