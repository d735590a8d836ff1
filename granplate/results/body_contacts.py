"""The granules' contacts on an elastic body in space at the output times
(docs/model.md section 3.9), recomputed from the recorded states by the loop's own
contact pass (solver.body.replay): which face each granule touches and where, the force
on the body and its normal magnitude. What the body's fields (results.body) spread as
static loads, and the Dataset's per-granule contact records."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import xarray as xr

from granplate.model.inputs import new_body_state


class BodyContacts(NamedTuple):
    """Each granule's contact on the body at each output time."""

    face: np.ndarray  # (nt, ng) int64: the surface face touched (solid.surface order), -1: none
    xi: np.ndarray  # (nt, ng, 2): the point's face coordinates
    force: np.ndarray  # (nt, ng, 3) [N]: the force on the body (global x, y, z)
    normal: np.ndarray  # (nt, ng) [N]: its normal magnitude |N|


def body_contacts(model, y: np.ndarray, q: np.ndarray, qd: np.ndarray) -> BodyContacts:
    """The BodyContacts of model's body at the recorded states y (nt, ng, 9), q, qd (nt, nm)."""
    from granplate.solver.body import replay

    nt, ng = y.shape[0], y.shape[1]
    out = BodyContacts(
        face=np.full((nt, ng), -1, np.int64),
        xi=np.zeros((nt, ng, 2)),
        force=np.zeros((nt, ng, 3)),
        normal=np.zeros((nt, ng)),
    )
    if nt and ng:
        b = new_body_state(model.body)
        replay(
            np.ascontiguousarray(y),
            np.ascontiguousarray(q),
            np.ascontiguousarray(qd),
            b,
            model.granular.radius,
            model.granular.mass,
            model.config.clip,
            out.face,
            out.xi,
            out.force,
            out.normal,
        )
    return out


def patch_forces(model, c: BodyContacts):
    """rows -> (b, n_red) [N] sparse: the nodal forces of the contacts at those output
    times spread over their disc patches (solver.body.patch_loads), or None for point
    patches (results.body spreads those itself)."""
    import scipy.sparse as sp

    from granplate.solver.body import patch_loads

    b = new_body_state(model.body)
    if b.patch[0] == 0.0:
        return None
    n_red = b.phi.shape[0]
    room = 3 * b.entry.shape[2]

    def forces(rows):
        face = np.ascontiguousarray(c.face[rows])
        n_c = int((face >= 0).sum())
        t = np.empty(n_c * room, np.int64)
        col = np.empty(n_c * room, np.int64)
        val = np.empty(n_c * room)
        k = patch_loads(b, face, np.ascontiguousarray(c.xi[rows]), np.ascontiguousarray(c.force[rows]), t, col, val)
        out = sp.coo_matrix((val[:k], (t[:k], col[:k])), shape=(face.shape[0], n_red)).tocsr()
        out.sum_duplicates()
        return out

    return forces


def contact_variables(c: BodyContacts) -> dict[str, xr.DataArray]:
    """The Dataset's records of the body's contacts."""
    return {
        "body_contact_normal_force": xr.DataArray(
            c.normal,
            dims=("time", "granule"),
            attrs={"units": "N", "long_name": "normal force of each granule's contact on the elastic body (0: none)"},
        ),
        "body_contact_force": xr.DataArray(
            c.force,
            dims=("time", "granule", "component"),
            attrs={"units": "N", "long_name": "force on the elastic body at each granule's contact (x, y, z)"},
        ),
        "body_contact_face": xr.DataArray(
            c.face,
            dims=("time", "granule"),
            attrs={"long_name": "boundary face each granule touches (solid.surface order; -1: none)"},
        ),
        "body_contact_xi": xr.DataArray(
            c.xi,
            dims=("time", "granule", "face_coordinate"),
            attrs={"long_name": "the contact point's reference coordinates on its face"},
        ),
    }
