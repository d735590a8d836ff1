"""Honest first runs: what needs compiling is read from the loop's signatures, the compile
seconds are counted apart from the run's wall time, the progress bar starts after the
compile and shows no time left before its first output. Truth: numba's own compile events
(a function compiled on purpose inside the clock), the order of the driver's calls, and
tqdm's rendering of a bar that has not moved."""

from __future__ import annotations

import io
import time
import types

import pytest

#: A short run of two discs (the implicit scheme in the plane, compiled by the suite anyway).
TINY = """
name = "tiny"
[[granules]]
x = 0.01
y = 0.0
radius = 0.005
material = "steel"
vx = 1.0
[load]
kind = "none"
[time]
t_end = 2e-6
output_interval = 1e-6
"""


def _tiny():
    from granplate.setup.io import loads

    return loads(TINY)


def _fresh_function():
    """A numba function no cache holds (a new closure each call): calling it compiles."""
    from numba import njit

    salt = time.perf_counter()

    @njit
    def f(x):
        s = 0.0
        for i in range(x.shape[0]):
            s += x[i] * salt
        return s

    return f


def test_loop_signatures_name_their_scheme_dimension_and_solid():
    """(scheme, dimension, solid) of loop.advance's signature: the scratch's module names the
    scheme, the granular arrays' class the dimension, the body arrays' class whether the run
    has an elastic solid (model.inputs.BodyArrays; NoBodyArrays is a run without)."""
    from granplate.model.inputs import BodyArrays, Granular, Granular3, NoBodyArrays
    from granplate.solver.compiling import loop_key
    from granplate.solver.schemes import implicit, verlet

    def sig(g, sw, body=NoBodyArrays):
        def of(cls):
            return types.SimpleNamespace(instance_class=cls)

        return (None, None, of(g), None, of(body), None, None, None, of(sw), None)

    assert loop_key(sig(Granular3, verlet.Scratch)) == ("verlet", 3, False)
    assert loop_key(sig(Granular3, verlet.Scratch, BodyArrays)) == ("verlet", 3, True)
    assert loop_key(sig(Granular3, implicit.Scratch, BodyArrays)) == ("implicit", 3, True)
    assert loop_key(sig(Granular, implicit.Scratch)) == ("implicit", 2, False)
    assert loop_key(("too", "short")) is None


def test_missing_sets_are_those_whose_loop_is_not_compiled():
    """Every scheme in both dimensions is a kernel set; those whose loops the cache holds
    (with a solid too, for the sets that drive one) are not compiled again, and a run needs
    compiling only when its own is missing."""
    from granplate.results.kernels import KERNEL_SETS, missing, needs_compiling
    from granplate.setup.validate import SCHEMES

    assert {(k.scheme, k.dimension) for k in KERNEL_SETS} == {(s, d) for s in SCHEMES for d in (2, 3)}
    have = {("implicit", 2, False), ("verlet", 3, False), ("verlet", 3, True)}
    assert [k.name for k in missing(compiled=have)] == ["paper-2d", "verlet-2d", "implicit-3d", "paper-3d"]
    assert not needs_compiling(_tiny(), compiled=have)
    assert needs_compiling(_tiny(), compiled={("implicit", 3, False)})
    every = set().union(*(k.loops for k in KERNEL_SETS))
    alone = every - {("implicit", 3, True)}  # an older cache: the implicit loop in space without a solid
    assert [k.name for k in missing(compiled=alone)] == ["implicit-3d"]
    assert missing(compiled=every) == []


def test_the_compile_clock_counts_numbas_compiling_once():
    """A new function compiles inside the clock (seconds > 0); calling it again compiles
    nothing and adds nothing."""
    import numpy as np

    from granplate.solver.compiling import compile_clock

    f = _fresh_function()
    with compile_clock() as clock:
        f(np.ones(3))
        first = clock.seconds
        f(np.ones(3))
    assert first > 0.0 and clock.seconds == first


def test_the_loop_can_be_kept_in_the_disk_cache():
    """Every compiled time loop (solver.loop.advance) of this process can be written to
    numba's disk cache: none uses dynamic globals (numba's get_num_threads in the loop did,
    and then every new process compiled the loop again)."""
    from granplate.results.run import simulate
    from granplate.solver.loop import advance

    simulate(_tiny())
    libraries = [cres.library for cres in advance.overloads.values()]
    assert libraries and not any(lib.has_dynamic_globals for lib in libraries)


def test_summary_states_compile_seconds_apart_from_the_wall_time(monkeypatch):
    """A compile inside the run (a fresh function compiled while the model is built) is in
    compile_time_s, and wall_time_s leaves it out."""
    import numpy as np

    import granplate as gp
    from granplate.results import run as run_module

    build = run_module.build_model

    def compiling_build(s):
        _fresh_function()(np.ones(3))
        return build(s)

    monkeypatch.setattr(run_module, "build_model", compiling_build)
    t0 = time.perf_counter()
    ds = gp.simulate(_tiny(), progress=False)
    elapsed = time.perf_counter() - t0
    s = gp.summary(ds)
    assert s["compile_time_s"] > 0.0 and s["units"]["compile_time_s"] == "s"
    assert s["wall_time_s"] + s["compile_time_s"] <= elapsed


def test_the_bar_starts_after_the_compile_and_shows_no_time_left_before_an_output(monkeypatch):
    """The driver compiles (or loads) the loop before it makes the bar, and a bar that has
    not moved shows "?" for the time left, not an estimate."""
    from granplate.solver import driver

    order = []
    compile_calls, progress_bar = driver.compile_calls, driver.progress_bar
    monkeypatch.setattr(driver, "compile_calls", lambda calls: (order.append("compile"), compile_calls(calls)))
    monkeypatch.setattr(
        driver,
        "progress_bar",
        lambda total, desc: (order.append("bar"), progress_bar(total, desc, file=io.StringIO()))[1],
    )
    from granplate.results.run import simulate

    simulate(_tiny(), progress=True)
    assert order == ["compile", "bar"]
    bar = progress_bar(26500, "x", file=io.StringIO())
    assert "0/26500" in str(bar) and "<?" in str(bar)
    bar.close()


def test_compile_kernels_says_what_it_compiles_with_an_estimate():
    """One line per set naming the scheme and the dimension, with the measured estimate."""
    from granplate.results.kernels import KernelSet, compile_kernels

    said = []
    done = compile_kernels([KernelSet("implicit", 2, lambda: [_tiny()])], note=said.append)
    assert list(done) == ["implicit-2d"]
    assert any(line.startswith("compiling 1/1: the implicit scheme in the plane (about ") for line in said)
    assert said[-1].startswith("compiled 1 kernel sets in ")


def test_granplate_compile_has_nothing_to_do_when_every_set_is_cached(monkeypatch, capsys):
    """`granplate compile` with every loop in the cache compiles nothing."""
    from granplate import cli
    from granplate.results import kernels

    monkeypatch.setattr(kernels, "missing", lambda: [])
    assert cli.main(["compile"]) == 0
    assert "every scheme's kernels are compiled" in capsys.readouterr().out


@pytest.mark.parametrize("seconds, text", [(45.2, "45 s"), (250, "4 min 10 s")])
def test_estimates_read_in_minutes(seconds, text):
    from granplate.solver.compiling import describe_seconds

    assert describe_seconds(seconds) == text


def test_a_set_that_cannot_compile_does_not_stop_the_others():
    """A kernel set whose short run fails is reported and skipped; the next one compiles."""
    from granplate.results.kernels import KernelSet, compile_kernels

    def broken():
        raise RuntimeError("no such scenario")

    said = []
    done = compile_kernels(
        [KernelSet("paper", 3, broken), KernelSet("implicit", 2, lambda: [_tiny()])], note=said.append
    )
    assert list(done) == ["implicit-2d"]
    assert any("could not compile the paper scheme in space (RuntimeError: no such scenario)" in s for s in said)
