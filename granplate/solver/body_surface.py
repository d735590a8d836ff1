"""Where a granule touches an elastic body in space (docs/model.md section 3.9): the body's
bounding box, the closest point of the undeformed surface and its patch (the face's shape
functions there, or a disc of surface nodes about it) with the weights' gradients in the
granule's position, the surface's velocity and normal displacement at the contact, and a
force at the contact spread over the patch onto the modes, Phi^T (w (x) f).
"""

from __future__ import annotations

import math

import numpy as np
from granplate.jit import njit

from granplate.model.inputs import GEO_DIST, GEO_ETA, GEO_GX, GEO_GY, GEO_GZ, GEO_NX, GEO_NY, GEO_NZ, GEO_XI
from granplate.solid.surface import face_shape_functions, follow_closest


@njit(cache=True)
def near_box(b, x, y, z, reach) -> bool:
    """Whether a centre lies within `reach` [m] of the body's bounding box."""
    d2 = 0.0
    for c, v in ((0, x), (1, y), (2, z)):
        lo = b.box[0, c] - v
        hi = v - b.box[1, c]
        e = max(lo, hi, 0.0)
        d2 += e * e
    return d2 <= reach * reach


@njit(cache=True)
def tangent_map(X, dN, t) -> None:
    """t (3, 2) = J (J^T J)^-1, J = sum_a X_a grad_xi(N_a)^T the face's Jacobian at the
    point of the shape functions' derivatives dN: a face gradient to the surface gradient
    in space."""
    j00 = j01 = j10 = j11 = j20 = j21 = 0.0
    for a in range(dN.shape[0]):
        j00 += X[a, 0] * dN[a, 0]
        j01 += X[a, 0] * dN[a, 1]
        j10 += X[a, 1] * dN[a, 0]
        j11 += X[a, 1] * dN[a, 1]
        j20 += X[a, 2] * dN[a, 0]
        j21 += X[a, 2] * dN[a, 1]
    a00 = j00 * j00 + j10 * j10 + j20 * j20
    a01 = j00 * j01 + j10 * j11 + j20 * j21
    a11 = j01 * j01 + j11 * j11 + j21 * j21
    det = a00 * a11 - a01 * a01
    i00 = a11 / det
    i01 = -a01 / det
    i11 = a00 / det
    t[0, 0] = j00 * i00 + j01 * i01
    t[0, 1] = j00 * i01 + j01 * i11
    t[1, 0] = j10 * i00 + j11 * i01
    t[1, 1] = j10 * i01 + j11 * i11
    t[2, 0] = j20 * i00 + j21 * i01
    t[2, 1] = j20 * i01 + j21 * i11


@njit(cache=True)
def patch_frame(nx, ny, nz):
    """Two unit tangents (t1, t2) of the plane normal to n: t1 along e x n for the axis e
    least aligned with n (constant over a flat face), t2 = n x t1."""
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    if ax <= ay and ax <= az:  # e = x: e x n = (0, -nz, ny)
        t1x, t1y, t1z = 0.0, -nz, ny
    elif ay <= az:  # e = y: (nz, 0, -nx)
        t1x, t1y, t1z = nz, 0.0, -nx
    else:  # e = z: (-ny, nx, 0)
        t1x, t1y, t1z = -ny, nx, 0.0
    inv = 1.0 / math.sqrt(t1x * t1x + t1y * t1y + t1z * t1z)
    t1x *= inv
    t1y *= inv
    t1z *= inv
    return t1x, t1y, t1z, ny * t1z - nz * t1y, nz * t1x - nx * t1z, nx * t1y - ny * t1x


@njit(refcount=True, cache=True)
def locate(b, buf, i, p, out, N, dN) -> None:
    """Granule i's contact on the undeformed surface (docs/model.md section 3.9), centre p
    (3,) [m], into buffer buf: the closest point (face, face coordinates, signed distance,
    outward normal: geo), searched from the face it last touched; and its patch as entries
    (surface node, weight, the weight's gradient in the granule's position [1/m]): the
    face's shape functions at the point (radius b.patch[0] = 0), or the disc of that
    radius about the point (`disc_patch`)."""
    seed = b.face[buf, i] if b.face[buf, i] >= 0 else b.face[1 - buf, i]
    f = follow_closest(b.face_nodes, b.kind[0], b.neighbours, seed, p, out)
    b.face[buf, i] = f
    g = b.geo[buf, i]
    g[GEO_XI] = out[0]
    g[GEO_ETA] = out[1]
    g[GEO_NX] = out[5]
    g[GEO_NY] = out[6]
    g[GEO_NZ] = out[7]
    g[GEO_DIST] = out[8]
    if b.patch[0] > 0.0:
        disc_patch(b, buf, i, out[2], out[3], out[4], out[5], out[6], out[7])
        return
    face_shape_functions(b.kind[0], out[0], out[1], N, dN)
    t = np.empty((3, 2))
    tangent_map(b.face_nodes[f], dN, t)
    for a in range(N.shape[0]):
        b.entry[buf, i, a] = b.face_snode[f, a]
        b.weights[buf, i, a] = N[a]
        for c in range(3):
            b.grad[i, a, c] = t[c, 0] * dN[a, 0] + t[c, 1] * dN[a, 1]
    b.count[buf, i] = N.shape[0]


@njit(cache=True)
def disc_patch(b, buf, i, x0, x1, x2, nx, ny, nz) -> None:
    """Granule i's patch of radius a = b.patch[0] about the surface point x [m] (normal n):
    every surface node within a of x, weighted by its share of the surface times the kernel
    (1 - r^2/a^2)^2 and normalised, so that the weights are smooth in x and, as the mesh is
    refined, average the surface over the disc; their gradients in the granule's position
    are the kernel's along the surface (I - n n^T). Nodes by the grid of cells of b.grid."""
    a = b.patch[0]
    cell = b.grid[0]
    o0, o1, o2 = b.grid_origin[0], b.grid_origin[1], b.grid_origin[2]
    s0, s1, s2 = b.grid_shape[0], b.grid_shape[1], b.grid_shape[2]
    c0 = int((x0 - o0) / cell)
    c1 = int((x1 - o1) / cell)
    c2 = int((x2 - o2) / cell)
    n = 0
    total = 0.0
    dt0 = dt1 = dt2 = 0.0
    inv_a2 = 1.0 / (a * a)
    for k0 in range(max(c0 - 1, 0), min(c0 + 2, s0)):
        for k1 in range(max(c1 - 1, 0), min(c1 + 2, s1)):
            for k2 in range(max(c2 - 1, 0), min(c2 + 2, s2)):
                cid = (k0 * s1 + k1) * s2 + k2
                for q in range(b.cell_start[cid], b.cell_start[cid + 1]):
                    node = b.cell_nodes[q]
                    d0 = b.node_xyz[node, 0] - x0
                    d1 = b.node_xyz[node, 1] - x1
                    d2 = b.node_xyz[node, 2] - x2
                    rho2 = (d0 * d0 + d1 * d1 + d2 * d2) * inv_a2
                    if rho2 >= 1.0 or n >= b.entry.shape[2]:
                        continue
                    one = 1.0 - rho2
                    k = b.node_area[node] * one * one
                    dk = b.node_area[node] * 4.0 * one * inv_a2  # dk/dx = dk * (X_node - x)
                    b.entry[buf, i, n] = node
                    b.weights[buf, i, n] = k
                    b.grad[i, n, 0] = dk * d0
                    b.grad[i, n, 1] = dk * d1
                    b.grad[i, n, 2] = dk * d2
                    total += k
                    dt0 += dk * d0
                    dt1 += dk * d1
                    dt2 += dk * d2
                    n += 1
    b.count[buf, i] = n
    inv = 1.0 / total
    for e in range(n):
        w = b.weights[buf, i, e] * inv
        b.weights[buf, i, e] = w
        g0 = (b.grad[i, e, 0] - w * dt0) * inv
        g1 = (b.grad[i, e, 1] - w * dt1) * inv
        g2 = (b.grad[i, e, 2] - w * dt2) * inv
        gn = g0 * nx + g1 * ny + g2 * nz  # along the surface only: the foot moves tangentially
        b.grad[i, e, 0] = g0 - gn * nx
        b.grad[i, e, 1] = g1 - gn * ny
        b.grad[i, e, 2] = g2 - gn * nz


@njit(refcount=True, cache=True)
def surface_velocity(b, buf, i, qd):
    """The surface's velocity at granule i's contact (buffer buf), its patch's weighted mean
    sum_e w_e Phi_e qd [m/s] (x, y, z)."""
    nm = qd.shape[0]
    v = np.zeros(3)
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e]
        if w == 0.0:
            continue
        node = b.entry[buf, i, e]
        for c in range(3):
            row = b.node_rows[node, c]
            if row < 0:
                continue
            sv = 0.0
            for m in range(nm):
                sv += b.phi[row, m] * qd[m]
            v[c] += w * sv
    return v[0], v[1], v[2]


@njit(cache=True)
def normal_motion(b, buf, i, q) -> float:
    """The surface's normal displacement u_n = n . u_c [m] at granule i's contact (buffer
    buf; u_c its patch's weighted mean), and its gradient in the granule's position (the
    deformed surface's tilt, [-]) into geo's GEO_GX..GEO_GZ: sum_e grad(w_e) n . u_e."""
    g = b.geo[buf, i]
    nm = q.shape[0]
    un = 0.0
    gx = 0.0
    gy = 0.0
    gz = 0.0
    for e in range(b.count[buf, i]):
        node = b.entry[buf, i, e]
        ua = 0.0
        for c in range(3):
            row = b.node_rows[node, c]
            nc = g[GEO_NX + c]
            if row < 0 or nc == 0.0:
                continue
            sq = 0.0
            for m in range(nm):
                sq += b.phi[row, m] * q[m]
            ua += nc * sq
        un += b.weights[buf, i, e] * ua
        gx += b.grad[i, e, 0] * ua
        gy += b.grad[i, e, 1] * ua
        gz += b.grad[i, e, 2] * ua
    g[GEO_GX] = gx
    g[GEO_GY] = gy
    g[GEO_GZ] = gz
    return un


@njit(cache=True)
def spread(b, buf, i, fx, fy, fz, out, scale) -> None:
    """out[m] += scale * (Phi^T f)_m for the force f [N] at granule i's contact (buffer
    buf), spread over its patch's nodes by the weights."""
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e] * scale
        if w == 0.0:
            continue
        node = b.entry[buf, i, e]
        for c in range(3):
            row = b.node_rows[node, c]
            if row < 0:
                continue
            fc = w * (fx if c == 0 else (fy if c == 1 else fz))
            for m in range(out.shape[0]):
                out[m] += b.phi[row, m] * fc


@njit(cache=True)
def spread_both(b, buf, i, nx, ny, nz, n, d, out, out_d) -> None:
    """out += Phi^T (w (x) n N) and out_d += Phi^T (w (x) n D) in one pass over the rows:
    a normal force N n and its damping part D n [N] at granule i's contact."""
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e]
        if w == 0.0:
            continue
        node = b.entry[buf, i, e]
        for c in range(3):
            row = b.node_rows[node, c]
            nc = nx if c == 0 else (ny if c == 1 else nz)
            if row < 0 or nc == 0.0:
                continue
            fc = w * nc * n
            fd = w * nc * d
            for m in range(out.shape[0]):
                phi = b.phi[row, m]
                out[m] += phi * fc
                out_d[m] += phi * fd
