"""Follow a running study: `granplate study report DIR --watch` polls the study folder,
writes the interactive page again whenever a design's record arrives (the page says how
many designs are done, failed and left, and reloads itself while some are left), and
writes the full report (figures, Markdown) once none is left (docs/studies.md).

    >>> from granplate.study.watch import watch
    >>> watch("q0-r2", every=5.0)      # returns the final counts; Ctrl-C stops it
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

from granplate.study import design as D

#: Seconds between two looks at the study folder.
EVERY_S = 5.0
#: Said while a study has its study file but nothing to read yet (an optimisation writes
#: trials.csv after its first trials).
WAITING = "watch: waiting for the study's first table (trials.csv)"


def folder_state(folder: Path) -> tuple:
    """What the page is drawn from, cheaply: the records' names, sizes and times, and the
    tables' and study file's times (a change in any means a new page)."""
    designs = Path(folder) / D.DESIGNS
    records = (
        sorted((p.name, p.stat().st_size, p.stat().st_mtime_ns) for p in designs.glob("*.json"))
        if designs.is_dir()
        else []
    )
    tables = [
        (n, (Path(folder) / n).stat().st_mtime_ns)
        for n in ("study.toml", "trials.csv", "results.nc", "results.csv")
        if (Path(folder) / n).is_file()
    ]
    return tuple(records), tuple(tables)


def counts_line(c: dict[str, int]) -> str:
    """'watch: 12 done, 1 failed, 23 left of 36'."""
    return f"watch: {c['done']} done, {c['failed']} failed, {c['left']} left of {c['total']}"


def watch(
    folder: str | Path,
    every: float = EVERY_S,
    echo: Callable[[str], None] = print,
    rounds: int | None = None,
    final: bool = True,
) -> dict[str, int]:
    """Poll `folder` every `every` seconds; on a change write the live page and echo the
    counts; once no design is left (or after `rounds` looks), write the final page (the
    full report when `final`, else the page without its reload) and return the counts.
    A KeyboardInterrupt writes the page without its reload first, then propagates."""
    from granplate.errors import ScenarioError
    from granplate.study.outcome import STUDY_FILE
    from granplate.study.report import write_live_page, write_report

    folder = Path(folder)
    last, c, n = None, None, 0
    try:
        while True:
            state = folder_state(folder)
            if state != last:
                try:
                    _, c = write_live_page(folder)
                    echo(counts_line(c))
                except ScenarioError:
                    if not (folder / STUDY_FILE).is_file():
                        raise  # no study here at all
                    if last is None:  # an optimisation before its first table
                        echo(WAITING)
                last = state
            n += 1
            if (c is not None and c["left"] == 0) or (rounds is not None and n >= rounds):
                break
            time.sleep(every)
    except KeyboardInterrupt:
        if c is not None:
            write_live_page(folder, live=False)
        raise
    if c is None:
        return {"total": 0, "done": 0, "failed": 0, "left": 0, "infeasible": 0}
    if final and c["left"] == 0:
        write_report(folder, live=True)
    else:
        write_live_page(folder, live=False)
    return c
