"""The runs, figures and animations of `granplate reproduce` as tasks of the distributed
engine (`granplate.results.engine`): progress on stderr, and the driver that submits the
runs longest first and each figure or animation as soon as the runs it needs are in.

The tasks read and write the output folder, so the workers of a cluster given by
`--scheduler` must see it (the same machine, or a shared file system).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from granplate.results import engine
from granplate.paper.reproduce import (
    Job,
    Outcome,
    RunRecord,
    expected_cost,
    make_animation,
    make_figure,
    run_job,
)


class Progress:
    """Progress on stderr: one line per finished task, and a bar on a terminal."""

    def __init__(self, total: int, quiet: bool = False):
        self.quiet = quiet
        self.done = 0
        self.total = total
        self.bar = None
        if not quiet and sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc="reproduce", unit="task", leave=False)

    def add(self, n: int) -> None:
        self.total += n
        if self.bar is not None:
            self.bar.total = self.total
            self.bar.refresh()

    def step(self, line: str) -> None:
        self.done += 1
        text = f"[{self.done}/{self.total}] {line}"
        if self.bar is not None:
            self.bar.update(1)
            self.bar.write(text, file=sys.stderr)
        elif not self.quiet:
            print(text, file=sys.stderr, flush=True)

    def note(self, line: str) -> None:
        if self.bar is not None:
            self.bar.write(line, file=sys.stderr)
        elif not self.quiet:
            print(line, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@dataclass(frozen=True)
class Product:
    """A figure (key: the figure's name) or an animation (key: the run animated) waiting
    for the runs it needs."""

    kind: str
    key: str
    needs: tuple[str, ...]

    @property
    def label(self) -> str:
        return f"{self.kind} {self.key}"


class Driver:
    """Runs the jobs on a Dask client and starts each figure / animation once its runs are in."""

    def __init__(
        self,
        client,
        outcome: Outcome,
        products: list[Product],
        available: dict[str, Path],
        progress: Progress,
        frames: int | None,
    ):
        from distributed import as_completed

        self.client, self.outcome, self.products = client, outcome, products
        self.available, self.failed = available, set()
        self.progress, self.frames = progress, frames
        self.running: dict = {}
        self.pending = as_completed()

    def submit(self, kind: str, what, function, *args, priority: int = 0) -> None:
        """One task (a run, a figure or an animation) on the cluster."""
        fut = self.client.submit(function, *args, pure=False, priority=priority)
        self.running[fut] = (kind, what)
        self.pending.add(fut)

    def submit_runs(self, jobs: list[Job]) -> None:
        """Queue the simulations, longest first (finer meshes, steel packings)."""
        ordered = sorted(jobs, key=expected_cost, reverse=True)
        for rank, job in enumerate(ordered):
            self.submit("run", job, run_job, job, priority=len(ordered) - rank)

    def launch_ready(self) -> None:
        """Start every product whose runs are all in; drop those whose runs failed."""
        out = self.outcome.out_dir
        for prod in list(self.products):
            lost = [n for n in prod.needs if n in self.failed]
            if lost:
                self.products.remove(prod)
                self.outcome.problems.append(f"{prod.label} not made: run {', '.join(lost)} failed")
                self.progress.step(f"skipped {prod.label}")
            elif all(n in self.available for n in prod.needs):
                self.products.remove(prod)
                paths = [self.available[n] for n in prod.needs]
                if prod.kind == "figure":
                    self.submit(prod.kind, prod, make_figure, prod.key, paths, out / "figures")
                else:
                    self.submit(
                        prod.kind, prod, make_animation, paths[0], out / "animations" / f"{prod.key}.mp4", self.frames
                    )

    def finish(self, fut) -> None:
        """Record one finished task (a run, a figure or an animation)."""
        kind, what = self.running.pop(fut)
        if kind == "run":
            try:
                rec = fut.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker: report, go on
                rec = RunRecord(what.name, what.path, "failed", 0.0, repr(exc), what.kind)
            self.outcome.runs.append(rec)
            if rec.status == "ran":
                self.available[rec.name] = rec.path
                self.progress.step(f"ran {rec.name} in {rec.seconds:.1f} s -> {rec.path}")
            else:
                self.failed.add(rec.name)
                self.outcome.problems.append(f"run {rec.name} failed: {rec.message}")
                self.progress.step(f"FAILED {rec.name}: {rec.message}")
            self.launch_ready()
            return
        try:
            res = fut.result()
        except Exception as exc:  # noqa: BLE001 - report, go on with the rest
            self.outcome.problems.append(f"{what.label} failed: {exc!r}")
            self.progress.step(f"FAILED {what.label}: {exc!r}")
            return
        if kind == "figure":
            self.outcome.figures[what.key] = res
            self.progress.step(f"drew {what.label} -> {res[0]}")
        else:
            self.outcome.animations.append(res)
            self.progress.step(f"made {what.label} -> {res}")

    def run(self, jobs: list[Job]) -> None:
        """Everything, to the end (products whose runs never come are left out); on an
        interruption the tasks not finished are cancelled."""
        self.submit_runs(jobs)
        self.launch_ready()
        try:
            for fut in self.pending:
                self.finish(fut)
        finally:
            engine.cancel(self.client, self.running)
