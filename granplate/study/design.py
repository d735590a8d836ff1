"""One design of a study: its identity, its run (a pure function of the scenario's TOML
text, run on a Dask worker) and its record on disk, DIR/designs/KEY.json.

A design's KEY is `granplate.store.key` of the changed scenario's TOML (gp.dumps) and the
granplate version: the same design in a rerun (or in another study) has the same record,
and another granplate version computes it again. Records are written atomically, one
per design as soon as it is in, so a killed sweep keeps every finished design.
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path
from typing import Any

import granplate as gp
from granplate import store
from granplate.errors import GranplateError

#: The run store kind (and format version) of a design's identity.
RECORD_KIND = "study-design"
RECORD_FORMAT = 1
#: Folder of the records inside a study's output folder.
DESIGNS = "designs"

#: Metrics a study adds to gp.summary: name -> (unit, meaning).
EXTRA_METRICS: dict[str, tuple[str, str]] = {
    "granular_mass": ("kg", "total mass of the granules (the protector)"),
    "max_von_mises_nodes": (
        "Pa",
        "largest von Mises stress at the plate's element nodes instead "
        "of its Gauss points (docs/model.md 4.4), from the stored plate "
        "displacements; only for a run that keeps them at every output "
        "(time.field_interval = time.output_interval), else null",
    ),
}


def nodal_von_mises(ds) -> float | None:
    """The largest von Mises stress [Pa] at the element nodes over the run, from the plate
    displacements; None unless the result has them at every output time (sampled more
    sparsely, the nodal maximum would not compare with max_von_mises)."""
    import numpy as np

    if "plate_ux" not in ds or not np.array_equal(ds["field_time"].values, ds["time"].values):
        return None
    from granplate.paper.checks import stress_series

    series = stress_series(ds, "nodes")
    return float(series.max()) if series.size else None


def keeps_every_field(scenario) -> bool:
    """Whether a design keeps the plate fields at every output time (time.field_interval =
    time.output_interval): then its whole result is built, for max_von_mises_nodes."""
    t = scenario.time
    return scenario.plate is not None and abs(t.field_interval - t.output_interval) <= 1e-9 * t.output_interval


#: Summary keys a design keeps among its timings, not its metrics (loop_time_s: timings' loop_s).
TIMING_KEYS: tuple[str, ...] = ("loop_time_s",)


def metrics(ds) -> dict[str, Any]:
    """gp.summary of a result, less TIMING_KEYS, with the study's extra metrics (and their
    units) added."""
    summary = {k: v for k, v in gp.summary(ds).items() if k not in TIMING_KEYS}
    summary["units"] = {k: u for k, u in summary.get("units", {}).items() if k not in TIMING_KEYS}
    summary["granular_mass"] = float(ds["mass"].sum()) if "mass" in ds else None
    summary["max_von_mises_nodes"] = nodal_von_mises(ds)
    summary["units"] = {**summary.get("units", {}), **{k: u for k, (u, _) in EXTRA_METRICS.items()}}
    return summary


def metric_units() -> dict[str, str]:
    """Every metric a design has (gp.summary's and the extra ones) and its unit."""
    from granplate.results.dataset import SUMMARY_UNITS

    units = {k: u for k, u in SUMMARY_UNITS.items() if k not in TIMING_KEYS}
    return {**units, **{k: u for k, (u, _) in EXTRA_METRICS.items()}}


def design_key(scenario_toml: str) -> str:
    """The design's identity: SHA-256 of its scenario's TOML and the granplate version."""
    return store.key(RECORD_KIND, scenario_toml, RECORD_FORMAT)


def failure_message(err: BaseException) -> str:
    """A failure as one line: the exception's class and message."""
    return f"{type(err).__name__}: {err}".replace("\n", " ")


#: At most this many distinct warnings of a design's run are kept in its record.
MAX_WARNINGS = 5


def run_warnings(caught: list) -> list[str]:
    """The distinct warnings a design's run raised, one line each ("Category: message"),
    at most MAX_WARNINGS, in the order raised."""
    out: list[str] = []
    for w in caught:
        line = f"{w.category.__name__}: {w.message}".replace("\n", " ")
        if line not in out:
            out.append(line)
    return out[:MAX_WARNINGS]


def note_warnings(report, label: str, outcome: dict) -> None:
    """Count a design whose run warned in a sweep's or an optimisation's report (n_warned),
    and keep the first such warning (first_warning, "LABEL: warning")."""
    if outcome.get("warnings"):
        report.n_warned += 1
        if not report.first_warning:
            report.first_warning = f"{label}: {outcome['warnings'][0]}"


def run_design(scenario_toml: str, full: bool = False) -> dict[str, Any]:
    """Simulate one design (runs on a worker): {"status", "summary", "elapsed_s",
    "timings", "result", "warnings"}.

    status is "ok" or the failure message (a scenario the physics refuses, a run that goes
    numerically wrong, or any other error: a failing design never stops a sweep); summary
    is `metrics` of the run: gp.summary and EXTRA_METRICS (None on failure); elapsed_s the
    task's seconds on its worker, all included; timings the run's set-up, first-call and
    loop seconds and the loop's CPU seconds (`timings`), the summary's (summary_s: the result and its metrics after
    the loop) and the task's CPU seconds (cpu_s; {} on failure); result the Dataset when full, else None (and then only
    what the summary reads is computed, unless the design keeps its plate fields at every
    output time, `keeps_every_field`, for the nodal stress); warnings the distinct warnings
    the run raised (`run_warnings`), kept in the record instead of printed by the worker
    (the sweep counts them).
    """
    t0, c0 = time.perf_counter(), time.thread_time()
    ds = summary = None
    after_loop = 0.0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            scenario = gp.loads(scenario_toml)
            t1 = time.perf_counter()
            ds = gp.simulate(scenario, progress=False, summary_only=not (full or keeps_every_field(scenario)))
            summary = metrics(ds)
            after_loop = (
                time.perf_counter()
                - t1
                - float(ds.attrs.get("wall_time_s", 0.0))
                - float(ds.attrs.get("compile_time_s", 0.0))
            )  # wall_time_s leaves compiling out
            status = "ok"
        except GranplateError as err:
            status = failure_message(err)
        except Exception as err:  # noqa: BLE001 - recorded as the design's failure
            status = failure_message(err)
    return {
        "status": status,
        "summary": summary,
        "elapsed_s": time.perf_counter() - t0,
        "timings": (
            {**timings(ds), "summary_s": after_loop, "cpu_s": time.thread_time() - c0} if summary is not None else {}
        ),
        "result": ds if full and summary is not None else None,
        "warnings": run_warnings(caught),
    }


def timings(ds) -> dict[str, float]:
    """Where a design's run spent its time [s]: set-up (the model), the loop's first call
    (its initial state and output row, kernels loaded), the time loop, and the loop's CPU
    time in its thread (loop_cpu_s; the task's is cpu_s)."""
    return {
        "setup_s": float(ds.attrs.get("setup_time_s", 0.0)),
        "first_call_s": float(ds.attrs.get("first_call_time_s", 0.0)),
        "loop_s": float(ds.attrs.get("loop_time_s", 0.0)),
        "loop_cpu_s": float(ds.attrs.get("loop_thread_cpu_s", ds.attrs.get("loop_cpu_s", 0.0))),
    }


# ------------------------------------------------------------------------- records


def record_path(out: str | Path, key: str, suffix: str = ".json") -> Path:
    return Path(out) / DESIGNS / f"{key}{suffix}"


def make_record(key: str, changes: dict, scenario_toml: str, outcome: dict) -> dict:
    """The JSON record of a finished design."""
    return {
        "key": key,
        "granplate_version": gp.__version__,
        "status": outcome["status"],
        "changes": changes,
        "summary": outcome["summary"],
        "elapsed_s": outcome["elapsed_s"],
        "timings": outcome.get("timings", {}),
        "warnings": outcome.get("warnings", []),
        "scenario_toml": scenario_toml,
    }


def write_record(out: str | Path, record: dict, result=None) -> Path:
    """Write designs/KEY.json atomically (and KEY.nc first, with the full result)."""
    if result is not None:
        store.atomic_write(record_path(out, record["key"], ".nc"), lambda tmp: gp.write(result, tmp))
    text = json.dumps(record, indent=1) + "\n"
    return store.atomic_write(record_path(out, record["key"]), lambda tmp: tmp.write_text(text))


def read_record(out: str | Path, key: str, full: bool = False) -> dict | None:
    """The record of design KEY, or None when missing, unreadable or of another key (and,
    with full, when a successful design's KEY.nc is missing)."""
    path = record_path(out, key)
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("key") != key or "status" not in record:
        return None
    if full and record["status"] == "ok" and not record_path(out, key, ".nc").is_file():
        return None
    return record
