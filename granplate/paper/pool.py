"""The process pool behind `granplate reproduce`: worker threads per process, the
spawned pool, progress on stderr, and the driver that starts each figure or animation as
soon as the runs it needs are in.
"""
from __future__ import annotations

import os
import sys
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

from granplate.paper.reproduce import (
    Job, Outcome, RunRecord, expected_cost, make_animation, make_figure, run_job,
)

#: Thread-count variables of the BLAS / OpenMP libraries the workers use.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


@contextmanager
def worker_threads(n_workers: int):
    """Share the cores among the workers: each worker's BLAS gets cores // workers threads
    (the workers inherit the environment; variables the user set are left alone)."""
    per = str(max(1, (os.cpu_count() or 1) // max(1, n_workers)))
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    try:
        for k in THREAD_VARIABLES:
            os.environ.setdefault(k, per)
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@contextmanager
def executor(n_jobs: int):
    """A pool of n_jobs spawned workers (clean: no forked numba / thread state); on the way
    out, queued tasks are cancelled (an interrupt does not wait for them)."""
    pool = ProcessPoolExecutor(max_workers=max(1, n_jobs), mp_context=get_context("spawn"))
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


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
    """Runs the jobs on a pool and starts each figure / animation once its runs are in."""

    def __init__(self, pool: ProcessPoolExecutor, outcome: Outcome, products: list[Product],
                 available: dict[str, Path], progress: Progress, frames: int | None):
        self.pool, self.outcome, self.products = pool, outcome, products
        self.available, self.failed = available, set()
        self.progress, self.frames = progress, frames
        self.running: dict[Future, tuple[str, object]] = {}

    def submit_runs(self, jobs: list[Job]) -> None:
        """Queue the simulations, longest first (finer meshes, steel packings)."""
        for job in sorted(jobs, key=expected_cost, reverse=True):
            self.running[self.pool.submit(run_job, job)] = ("run", job)

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
                    fut = self.pool.submit(make_figure, prod.key, paths, out / "figures")
                else:
                    fut = self.pool.submit(make_animation, paths[0], out / "animations" / f"{prod.key}.mp4",
                                           self.frames)
                self.running[fut] = (prod.kind, prod)

    def finish(self, fut: Future) -> None:
        """Record one finished task (a run, a figure or an animation)."""
        kind, what = self.running.pop(fut)
        if kind == "run":
            try:
                rec = fut.result()
            except Exception as exc:  # noqa: BLE001 - a crashed worker: report, go on
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
        """Everything, to the end (products whose runs never come are left out)."""
        self.submit_runs(jobs)
        self.launch_ready()
        while self.running:
            done, _ = wait(list(self.running), return_when=FIRST_COMPLETED)
            for fut in done:
                self.finish(fut)
