"""The full-length runs of the slow cases (`granplate verify --full`), computed side by
side on the distributed engine (`granplate.results.engine`) before the cases read them.

The slow cases (coupled.py's convergence studies, conservation.py's full-length energy
residuals) take each run's summary from `coupled.study_run`. `compute_missing` lists those
runs, computes the ones that neither the page's run cache nor the run store holds, as
Dask tasks (`coupled.run_summary`, longest first), and keeps each summary as it comes in;
the cases then only read them. An interruption keeps every finished run, and a run that
fails is left to its case (which computes it again and reports the failure).
"""

from __future__ import annotations

from typing import Callable

from .base import Context


def long_runs() -> list:
    """Every distinct full-length run of the slow cases (scenarios, first occurrence order)."""
    from .conservation import full_runs
    from .coupled import cache_key, study_scenarios

    seen, out = set(), []
    for s in [s for _, _, s in study_scenarios()] + [s for _, s in full_runs()]:
        k = cache_key(s)
        if k not in seen:
            seen.add(k)
            out.append(s)
    return out


def expected_cost(scenario) -> float:
    """A rough cost for ordering: elements x steps (finer meshes and steps first)."""
    p = scenario.plate
    elements = p.nx * p.ny if p is not None else 1
    return elements * scenario.time.t_end / scenario.time.dt_max


def compute_missing(
    ctx: Context,
    *,
    client=None,
    workers: int | None = None,
    scheduler: str | None = None,
    log: Callable[[str], None] | None = None,
) -> int:
    """Compute the long runs neither ctx.run_cache nor the run store holds, on the Dask
    cluster (client, else a local one of `workers` or the one at `scheduler`); the number
    computed."""
    from contextlib import nullcontext

    from distributed import as_completed

    from granplate.results import engine
    from granplate.setup.io import dumps

    from .coupled import keep_run, run_summary, stored_run

    missing = sorted((s for s in long_runs() if stored_run(ctx, s) is None), key=expected_cost, reverse=True)
    if not missing:
        return 0
    if log:
        log(f"verify: {len(missing)} full-length runs to compute on Dask ...")
    n = 0
    with (
        nullcontext(client)
        if client is not None
        else engine.dask_client(min(workers or engine.available_cores(), len(missing)), scheduler)
    ) as c:
        texts = [dumps(s) for s in missing]
        engine.warm_workers(c, texts[-1:])  # the cheapest: compiles the paper scheme's kernels
        futures = {
            c.submit(run_summary, text, pure=False, priority=len(texts) - i): s
            for i, (s, text) in enumerate(zip(missing, texts))
        }
        try:
            for fut in as_completed(futures):
                s = futures.pop(fut)
                try:
                    summ = fut.result()
                except Exception as err:  # noqa: BLE001 - its case runs it again and reports
                    if log:
                        log(
                            f"verify: a full-length run failed ({type(err).__name__}: {err}); "
                            "its case will run it again"
                        )
                    continue
                keep_run(ctx, s, summ)
                n += 1
                if log:
                    log(f"verify: full-length run {n}/{len(missing)} done ({summ['wall_time_s']:.0f} s)")
        finally:
            engine.cancel(c, futures)
    return n
