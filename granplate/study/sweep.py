"""Run a study's designs on Dask distributed and write its table (docs/studies.md).

The designs are tasks of the distributed engine (`granplate.results.engine`): by default
a LocalCluster of worker processes with one thread each, or an existing cluster given by
its scheduler's address. Before the designs, every worker is warmed up (the compiled
kernels loaded, the first design's plate model built once into the run store, where every
worker finds it: designs with the same plate share one model).

Results are gathered with `as_completed`: each design's record is written as soon as it
is in, so an interrupted sweep, a killed worker or a lost scheduler loses only the designs
in flight, and a rerun computes only the designs without a record. The table (results.nc,
results.csv) is written at the end, and also when the sweep is interrupted.
"""

from __future__ import annotations

import hashlib
import json
import sys
import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path

import granplate as gp
from granplate.results import engine
from granplate.results.engine import dask_client
from granplate.study import design as D
from granplate.study import table as T
from granplate.study.spec import Study

#: Table files inside a study's output folder.
RESULTS_NC = "results.nc"
RESULTS_CSV = "results.csv"
#: Beside the table: the SHA-256 of what it was written from (`table_inputs_hash`).
RESULTS_HASH = "results.sha256"


@dataclass
class SweepReport:
    """What a sweep did: designs in the study, found already done, computed now, failed
    (among all recorded), lost (a task that did not come back: no record, a rerun retries);
    the seconds of the whole sweep, of the designs' tasks (compute_s), of writing their
    records (store_s) and of the workers' warm-up; the designs computed now whose run
    warned (n_warned; each record lists its warnings) and the first of those warnings."""

    n_designs: int
    n_done_before: int
    n_computed: int = 0
    n_failed: int = 0
    lost: list[str] = field(default_factory=list)
    elapsed_s: float = 0.0
    compute_s: float = 0.0
    store_s: float = 0.0
    warm_up_s: float = 0.0
    n_warned: int = 0
    first_warning: str = ""
    out: Path = Path(".")


def warm_workers(client, scenario_toml: str) -> float:
    """Warm every worker up on one design (`engine.warm_workers`); the seconds."""
    return engine.warm_workers(client, [scenario_toml])


def progress_bar(total: int, initial: int, enabled: bool, desc: str = "sweep", unit: str = "design"):
    """A tqdm bar with ETA on stderr, labelled `desc`, counting `unit`s."""
    from tqdm import tqdm

    return tqdm(
        total=total, initial=initial, desc=desc, unit=unit, file=sys.stderr, disable=not enabled, dynamic_ncols=True
    )


def table_inputs_hash(study: Study, keys: list[str], records: list, attrs: dict) -> str:
    """SHA-256 of everything the table is written from: its attributes (the granplate
    version among them), the parameters, the designs, their keys and records."""
    text = json.dumps([attrs, list(study.names), study.designs, keys, records], sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def write_table(study: Study, out: Path, keys: list[str]) -> Path:
    """Read every design's record and write results.nc and results.csv (kept as they are
    when written from the same inputs: `RESULTS_HASH`); the .nc path."""
    from granplate.store import atomic_write

    records = [D.read_record(out, k) for k in keys]
    attrs = {
        "base": study.base_name,
        "fixed": T.attrs_json(study.fixed),
        "parameters": T.attrs_json(list(study.names)),
        "granplate_version": gp.__version__,
        "n_designs": len(keys),
        "n_ok": sum(1 for r in records if r and r["status"] == "ok"),
    }
    digest = table_inputs_hash(study, keys, records, attrs)
    stored = out / RESULTS_HASH
    if (
        (out / RESULTS_NC).is_file()
        and (out / RESULTS_CSV).is_file()
        and stored.is_file()
        and stored.read_text().strip() == digest
    ):
        return out / RESULTS_NC
    stored.unlink(missing_ok=True)
    ds = T.to_dataset(study.names, study.designs, keys, records, attrs)
    T.write_netcdf(ds, out / RESULTS_NC)
    T.write_csv(ds, out / RESULTS_CSV)
    atomic_write(stored, lambda tmp: tmp.write_text(digest + "\n"))
    return out / RESULTS_NC


def sweep(
    study: Study,
    out: str | Path,
    *,
    client=None,
    workers: int | None = None,
    scheduler: str | None = None,
    full: bool = False,
    limit: int | None = None,
    progress: bool = True,
) -> SweepReport:
    """Compute the designs of `study` that have no record in out/designs, then write the
    table. client: an open Dask Client to use (else one is made from workers/scheduler,
    see `dask_client`); full: keep each design's whole result (designs/KEY.nc); limit:
    compute at most this many of the missing designs (None: all)."""
    t0 = time.perf_counter()
    out = Path(out)
    (out / D.DESIGNS).mkdir(parents=True, exist_ok=True)
    texts = [gp.dumps(study.scenario(i)) for i in range(len(study.designs))]
    keys = [D.design_key(t) for t in texts]
    missing: dict[str, int] = {}  # key -> first design with it (equal designs run once)
    for i, k in enumerate(keys):
        if k not in missing and D.read_record(out, k, full=full) is None:
            missing[k] = i
    n_before = sum(1 for k in keys if k not in missing)
    todo = list(missing.items())[: limit if limit is not None else None]
    report = SweepReport(len(keys), n_before, out=out)
    try:
        if todo:
            with nullcontext(client) if client is not None else dask_client(workers, scheduler) as c:
                report.warm_up_s = warm_workers(c, texts[todo[0][1]])
                _run(c, study, out, todo, texts, keys, full, progress, report)
    finally:
        write_table(study, out, keys)
        report.n_failed = sum(1 for k in set(keys) if (r := D.read_record(out, k)) and r["status"] != "ok")
        report.elapsed_s = time.perf_counter() - t0
    return report


def _run(
    client,
    study: Study,
    out: Path,
    todo: list[tuple[str, int]],
    texts: list[str],
    keys: list[str],
    full: bool,
    progress: bool,
    report: SweepReport,
) -> None:
    """Submit the designs, write each record as it comes in (cancel the rest on interrupt)."""
    from distributed import as_completed

    futures = {client.submit(D.run_design, texts[i], full, key=f"design-{k}", pure=False): (k, i) for k, i in todo}
    bar = progress_bar(len(set(keys)), len(set(keys)) - len(todo), progress)
    try:
        for fut in as_completed(futures):
            k, i = futures.pop(fut)
            try:
                outcome = fut.result()
            except Exception as err:  # noqa: BLE001 - a lost task: no record, a rerun retries
                report.lost.append(f"design {i}: {D.failure_message(err)}")
                bar.update(1)
                continue
            t_store = time.perf_counter()
            D.write_record(out, D.make_record(k, study.changes(i), texts[i], outcome), outcome.get("result"))
            report.store_s += time.perf_counter() - t_store
            report.n_computed += 1
            report.compute_s += outcome["elapsed_s"]
            D.note_warnings(report, f"design {i}", outcome)
            bar.update(1)
            if outcome["status"] != "ok":
                bar.write(f"design {i} failed: {outcome['status']}", file=sys.stderr)
    finally:
        bar.close()
        engine.cancel(client, futures)
