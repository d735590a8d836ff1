"""What the library announces before a slow step: the time loop's compile is announced
exactly when numba's on-disk cache does not hold it (a fresh cache, then a second
process), and a plate build by the time setup.plate_cost estimates for it."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from granplate.plate.build import NOTE_BUILD_SECONDS, build_note
from granplate.setup.plate_cost import build_estimate
from granplate.setup.scenario import Plate

PROBE = textwrap.dedent("""
    import types
    import numpy as np
    from granplate.cli import show_notes
    from granplate.solver.driver import is_compiled, note_compile
    from kernel import twice

    show_notes(quiet=False)
    model = types.SimpleNamespace(scenario=types.SimpleNamespace(solver=types.SimpleNamespace(scheme="paper")),
                                  config=types.SimpleNamespace(dimension=2))
    args = (np.ones(3),)
    said = note_compile(model, [(twice, args)])
    twice(*args)
    print(said, is_compiled(twice, args), is_compiled(twice, (1.0,)))
""")


def test_compile_is_announced_only_when_numbas_cache_lacks_it(tmp_path):
    """Truth: numba's cache of a new function is empty in the first process (announced,
    then compiled and cached) and holds it in the second (not announced); another
    argument type is not compiled in either."""
    (tmp_path / "kernel.py").write_text(
        "from numba import njit\n\n\n@njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n"
    )
    (tmp_path / "probe.py").write_text(PROBE)
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
        "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]),
    }
    runs = [
        subprocess.run(
            [sys.executable, str(tmp_path / "probe.py")],
            capture_output=True,
            text=True,
            env=env,
            cwd=tmp_path,
            timeout=300,
        )
        for _ in range(2)
    ]
    for r in runs:
        assert r.returncode == 0, r.stderr
    assert runs[0].stdout.split() == ["True", "True", "False"]
    assert "granplate: compiling the time loop of the paper scheme in the plane (about " in runs[0].stderr
    assert runs[1].stdout.split() == ["False", "True", "False"]
    assert "compiling" not in runs[1].stderr


def test_plate_build_is_announced_with_its_estimated_time():
    """Truth: setup.plate_cost's estimate, TRUNCATED_SECONDS_PER_DOF x dofs for the
    truncated basis; a build estimated under NOTE_BUILD_SECONDS is not announced."""
    plate = Plate(nx=16, ny=320, modes="truncated")
    seconds = build_estimate("truncated", 32_000, 641)[1]
    assert seconds >= NOTE_BUILD_SECONDS
    note = build_note(plate, "truncated", 32_000, 641)
    assert note.startswith("building the 16 x 320 plate: modes below 1e+06 Hz")
    assert f"(about {seconds:.0f} s; cached afterwards)" in note
    assert build_note(Plate(), "all", 1082, 81) is None  # the paper's 4 x 40 plate: about 1 s
