"""The arrays one run advances (the elastic bodies' arrays, the state, the scratch and the
outputs), grown as a whole when patch contacts form on the plate's face (docs/model.md
section 3.5), and the one path by which every patch contact is placed."""

from __future__ import annotations

import numpy as np

from granplate.model.arrays import Model, granular_with_patch_contacts
from granplate.model.inputs import new_body_state, no_body
from granplate.physics.contact import plate_overlap
from granplate.plate.face import patch_weights
from granplate.solver import loop, state as S
from granplate.solver.interface import set_face_weights
from granplate.solver.run_contacts import ContactLists
from granplate.solver.schedule import sensor_setup
from granplate.solver.schemes import scheme


class LoopArrays:
    """The arrays one run advances, replaced as a whole when a patch contact is added
    (their contact dimension grows): the elastic bodies, p (the modal plate: its contact
    rows are this run's own) and b (the elastic body in space with this run's own contact
    state, or NoBodyArrays: none), the state, the shared and the scheme's scratch and the
    outputs."""

    def __init__(self, model: Model, times: np.ndarray, nk: int):
        g, p, cfg = model.granular, model.plate_arrays, model.config
        ng, nm = model.n_granules, len(p.omega2)
        nc = S.STATE_COLUMNS[cfg.dimension]
        self.p = p._replace(phi_d=p.phi_d.copy(), resid=p.resid.copy()) if cfg.face_skin > 0.0 else p
        self.st = S.new_state(ng, nm, nk, nc)
        self.w = S.new_work(ng, nm, nk, len(p.face_y), nc, cfg.threads)
        if cfg.face_skin > 0.0 and p.resid_face.shape[0] > 0:  # the rigid layers' face weights: their node
            for k, y_k in enumerate(model.plate.contact_y[:nk]):
                first, last = patch_weights(p.face_y, float(y_k), 0.0, self.w.wface)
                set_face_weights(k, first, last, self.w)
        self.b = no_body(ng, nm) if model.body is None else new_body_state(model.body)
        self.sw = scheme(cfg.scheme).new_scratch(ng, nm, nk, body=model.body, threads=cfg.threads)
        ts, gs = sensor_setup(model, times)
        self.out = S.new_output(times, ng, nm, nk, nc, len(g.wall_load), len(g.drive_target), ts, gs)
        self.scheme = cfg.scheme
        self.sw_threads = cfg.threads

    def grow(self, nk_new: int) -> None:
        """Room for nk_new plate contacts: every array reallocated with the old values
        kept (contacts keep their indices; the new ones start at zero) and the per-level
        matrices marked stale."""
        st, w = self.st, self.w
        ng, nm = st.y.shape[0], st.q.shape[0]
        nc = st.y.shape[1]
        self.st = _copied(st, S.new_state(ng, nm, nk_new, nc))
        self.w = _copied(w, S.new_work(ng, nm, nk_new, len(w.wface), nc, len(w.wflag)))
        self.sw = _copied(self.sw, scheme(self.scheme).new_scratch(ng, nm, nk_new, threads=self.sw_threads))
        self.out = _copied(
            self.out,
            S.new_output(
                self.out.target,
                ng,
                nm,
                nk_new,
                nc,
                self.out.wall_force.shape[1],
                self.out.drive.shape[1],
                self.out.sensor_target,
                self.out.sensor_granule,
            ),
        )
        phi_d = np.zeros((2 * nk_new, nm))
        phi_d[: self.p.phi_d.shape[0]] = self.p.phi_d
        self.p = self.p._replace(phi_d=phi_d)
        if self.p.resid_face.shape[0] > 0:  # a truncated basis: the new contacts' static rows start at zero
            resid = np.zeros((2 * nk_new, 2 * nk_new))
            n = self.p.resid.shape[0]
            resid[:n, :n] = self.p.resid
            self.p = self.p._replace(resid=resid)
        self.w.g_ok[:] = 0
        self.st.clock[S.CUSTOM_H] = -1.0


#: Arrays of at least this many bytes have their pages mapped at set-up (`map_pages`).
MAP_BYTES = 1 << 20
#: Doubles per page of memory (4 KiB).
PAGE_DOUBLES = 512


def map_pages(*tuples) -> None:
    """Write one number of every page of the large arrays in the named tuples `tuples` (and
    their nested ones) back as it is, so that the kernel maps their pages now. numpy's
    zeros hands out pages that are mapped, and cleared, only when first written: in the
    loop's first steps, where at a million spheres that took about a second of its time.
    The contents do not change."""
    for tup in tuples:
        for value in tup:
            if (
                isinstance(value, np.ndarray)
                and value.nbytes >= MAP_BYTES
                and value.flags.c_contiguous
                and value.flags.writeable
            ):
                flat, step = value.reshape(-1).view(np.uint8), 8 * PAGE_DOUBLES
                flat[::step] = flat[::step].copy()  # (not a view onto itself: numpy would write nothing)
            elif isinstance(value, tuple) and hasattr(value, "_fields"):
                map_pages(value)


def _copied(old: tuple, new: tuple) -> tuple:
    """`new` (a named tuple of arrays, or of such tuples: the implicit scheme's scratch
    holding its body step) with each array's leading block taken from `old`'s."""
    for a, b in zip(old, new):
        if isinstance(a, tuple):
            _copied(a, b)
            continue
        b[tuple(slice(0, min(m, n)) for m, n in zip(a.shape, b.shape))] = a[
            tuple(slice(0, min(m, n)) for m, n in zip(a.shape, b.shape))
        ]
    return new


def near_face(model: Model, y: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Granules without a plate contact (free != 0) whose centre lies within the plate's
    height and whose surface is within contact.skin R of its undeformed face (docs/model.md
    section 3.5), ascending."""
    cfg, r = model.config, model.granular.radius
    inside = (cfg.plate_ylo < y[:, 1]) & (y[:, 1] < cfg.plate_yhi) & (free != 0)
    near = plate_overlap(y[:, 0], r * (1.0 + cfg.face_skin), cfg.plate_x0) > 0.0
    return np.flatnonzero(inside & near).astype(np.int64)


def add_patch_contacts(model: Model, lists: "ContactLists", arr: LoopArrays) -> int:
    """Give every granule near the face without a plate contact a patch contact
    centred at its height (docs/model.md section 3.5); returns how many were added."""
    return attach_patches(model, lists, arr, near_face(model, arr.st.y, arr.w.plate_free))


def attach_patches(model: Model, lists: "ContactLists", arr: LoopArrays, new: np.ndarray) -> int:
    """Give each granule of `new` (ascending) a patch contact centred at its height: the
    one path of every patch contact, those formed during the run (NEW_PLATE) and those of
    the granules touching the face between nodes at t = 0 (before the first step); returns
    how many were added."""
    new = np.asarray(new, np.int64)
    if len(new) == 0:
        return 0
    nk = len(lists.g.pc_i)
    lists.g = granular_with_patch_contacts(model, lists.g, new)
    arr.grow(nk + len(new))
    for k, i in enumerate(new, start=nk):
        loop.place_contact(arr.sw, k, float(arr.st.y[i, 1]), arr.st, arr.p, model.config, arr.w)
        lists.formed.append((int(i), float(arr.st.clock[S.T_NOW]), float(arr.st.y[i, 1])))
        arr.st.slip[k] = arr.st.y[i, 4] + model.granular.radius[i] * arr.st.y[i, 5] - arr.st.v[2 * k + 1]
    arr.w.plate_free[new] = 0
    return len(new)
