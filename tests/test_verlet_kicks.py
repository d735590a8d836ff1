"""The velocity-Verlet step's passes over the granules (solver.schemes.verlet_kicks): the
serial kicks in chunks against one pass over every granule."""

from __future__ import annotations

import numpy as np

from granplate.bench.scaling_space import launched_fcc
from granplate.model.arrays import build_model
from granplate.solver import granular3d, kicks
from granplate.solver.schemes import verlet_kicks as V


def _kick_arrays(seed: int):
    """A 1,372-granule FCC packing's granular arrays (more than one chunk of the serial
    kicks) and random state, accelerations, damping and load rows, the reference positions
    near the state's."""
    g = build_model(launched_fcc((7, 7, 7), t_end=1e-7, scheme="verlet")).granular
    rng = np.random.default_rng(seed)
    ng = g.mass.shape[0]
    y, acc, fdamp, fload = (rng.standard_normal((ng, 9)) for _ in range(4))
    yref = y + 1e-3 * rng.standard_normal((ng, 9))
    return g, y, acc, fdamp, fload, yref


def test_the_chunked_serial_kicks_are_the_whole_pass_bit_for_bit():
    """Truth: the kicks of solver.kicks over every granule at once, the kinetic energies'
    pass over the kicked state and the largest squared move (numpy); the serial step's
    kicks in chunks, which measure those as they go, give the same numbers bit for bit."""
    g, y, acc, fdamp, fload, yref = _kick_arrays(1)
    ng = y.shape[0]
    assert ng > V.CHUNK and ng % V.CHUNK  # several chunks, the last one short
    h = 1e-3
    ya, acca, preda = y.copy(), acc.copy(), np.zeros_like(y)
    wa = kicks.kick_drift(ya, ya, acca, fdamp, fload, h, preda, V.N_DRIFT, 0, ng, True, True, True, True)
    yb, accb, predb = y.copy(), acc.copy(), np.zeros_like(y)
    notes = np.zeros(V.N_NOTES)
    wb = V.first_kick_serial(yb, yb, accb, fdamp, fload, h, predb, True, True, True, True, yref, 3, notes)
    assert wa == wb and wa[0] != 0.0 and wa[1] != 0.0
    assert np.array_equal(ya, yb) and np.array_equal(acca, accb) and np.array_equal(preda, predb)
    assert notes[V.NOTE_MOVED] == (((yb[:, :3] - yref[:, :3]) ** 2).sum(axis=1)).max()
    assert notes[V.NOTE_MOVES_READY] == 1.0
    for divide in (False, True):
        ya, acca, dya = y.copy(), acc.copy(), np.zeros_like(y)
        if divide:
            args = (V.N_DRIFT, 3, g.mass, g.inertia, 0, ng, True, True)
            wa = kicks.divide_kick(ya, acca, fdamp, fload, 0.5 * h, dya, *args)
        else:
            wa = kicks.kick(ya, acca, fdamp, fload, 0.5 * h, dya, V.N_DRIFT, 0, ng, True, True)
        ke = granular3d.kinetic_energies(ya, g.mass, g.inertia)
        yb, accb, dyb = y.copy(), acc.copy(), np.zeros_like(y)
        notes = np.zeros(V.N_NOTES)
        wb = V.closing_kick_serial(yb, accb, fdamp, fload, 0.5 * h, dyb, True, True, g, True, divide, 3, notes)
        assert wa == wb
        assert np.array_equal(ya, yb) and np.array_equal(acca, accb) and np.array_equal(dya, dyb)
        assert tuple(notes[V.NOTE_KX : V.NOTE_KR + 1]) == ke and notes[V.NOTE_KE_READY] == 1.0
