"""The discrete system: total potential of body, contact and scalar unknowns (:class:`_System`).

Energy, gradient and tangent of the coupled displacement/angle unknowns, contact forces and
augmented-Lagrangian multipliers, penetration guards, the sparse linear solve and the
convergence test used by :mod:`.newton`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from envs.model.holding import NO_PATCH

from .body import _Body
from .contact import (
    _corner_feature,
    _JawCorner,
    _Obstacle,
    _Rim,
    _segment_gap_gradient,
    _vertex_distance_gradient,
    _with_hessian,
)


def _corner_terms(poly: np.ndarray, c: np.ndarray, radius_m: float
                  ) -> list[tuple[float, str, int, float]]:
    """The penalty terms of a jaw corner against the rim polygon: ``(gap, kind, index, sign)``
    each, ``kind`` and ``index`` the rim feature (:func:`_corner_feature`) and ``sign`` that of
    its distance function (the gap is ``sign * distance - radius_m``).

    A sharp corner (``radius_m = 0``, the tips) has one term, its signed distance to the
    nearest feature. A rounded corner (the groove's mouth edges) whose centre is outside the
    rim has one term per rim segment within ``radius_m`` of it (its distance to that segment):
    where the rim wraps around the edge, the corner presses the two segments on either side of
    a node at once, and the sum of their terms stays smooth as it slides (the nearest of them
    alone would switch from one to the other, a kink Newton's method cannot converge on). A
    rounded corner whose centre has entered the rim keeps the signed distance's one term.
    """
    centre_gap, kind, idx = _corner_feature(poly, c)
    if radius_m == 0.0 or centre_gap <= 0.0:
        # the segment's distance function is signed itself, the vertex's takes the sign
        sign = 1.0 if kind == "segment" else math.copysign(1.0, centre_gap)
        return [(centre_gap - radius_m, kind, idx, sign)]
    t = np.roll(poly, -1, axis=0) - poly
    xi = np.clip(np.sum(t * (c - poly), axis=1) / np.sum(t * t, axis=1), 0.0, 1.0)
    dist = np.linalg.norm(c - (poly + xi[:, None] * t), axis=1)
    terms = []
    for i in np.flatnonzero(dist < radius_m):
        if 0.0 < xi[i] < 1.0:
            # the signed distance to the segment's line is positive outside the rim
            d_line = (c[0] - poly[i, 0]) * t[i, 1] - (c[1] - poly[i, 1]) * t[i, 0]
            terms.append((float(dist[i]) - radius_m, "segment", int(i),
                          math.copysign(1.0, d_line)))
        else:
            vertex = int(i) if xi[i] == 0.0 else (int(i) + 1) % poly.shape[0]
            terms.append((float(dist[i]) - radius_m, "vertex", vertex, 1.0))
    return terms


class _System:
    """Total potential of body + contact + scalar unknowns, with free-dof bookkeeping."""

    def __init__(
        self,
        body: _Body,
        rim: _Rim,
        fixed_dofs: np.ndarray,
        obstacles: Sequence[_Obstacle],
        nq: int,
        q_potential: Callable[[np.ndarray, float], tuple[float, np.ndarray, np.ndarray]],
        penalty_pa_per_m: float,
        q_scale: np.ndarray,
        force_tol_n: float,
        length_scale_m: float,
        corners: Sequence[_JawCorner] = (),
        rim_order: np.ndarray | None = None,
    ) -> None:
        self.body = body
        self.rim = rim
        self.obstacles = list(obstacles)
        self.nq = nq
        self.q_potential = q_potential
        self.n = body.n
        self.ntot = body.n + nq
        free = np.ones(self.ntot, dtype=bool)
        free[fixed_dofs] = False
        self.free = np.nonzero(free)[0]
        self.k_node = penalty_pa_per_m * rim.weight_m2  # (m,) [N/m]
        self.multipliers = [np.zeros(rim.dofs.shape[0]) for _ in self.obstacles]
        self.q_scale = q_scale
        self.force_tol_n = force_tol_n
        self.length_scale_m = length_scale_m
        self._order: np.ndarray | None = None
        # convex jaw corners against the deformed rim polygon (rim nodes in counter-clockwise order)
        self.corners = list(corners)
        self.rim_order = rim_order
        if self.corners:
            poly = rim.ref_m[rim_order]
            seg = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
            thickness = float(rim.weight_m2.sum() / seg.sum())
            self.k_corner = penalty_pa_per_m * thickness * float(np.mean(seg))
        self.corner_multipliers = np.zeros(len(self.corners))
        # penetration cap of trial points: a quarter of the shortest rim segment
        ref = rim.ref_m[rim_order] if rim_order is not None else rim.ref_m
        seg_len = np.linalg.norm(np.diff(ref, axis=0), axis=1)
        self.pen_cap_m = 0.25 * float(np.min(seg_len))

    # positions of the rim nodes
    def rim_positions(self, x: np.ndarray) -> np.ndarray:
        return self.rim.ref_m + x[self.rim.dofs]

    def _contact(self, x: np.ndarray, load: float, want_tangent: bool):
        p = self.rim_positions(x)
        energy = 0.0
        grad = np.zeros(self.ntot)
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        forces = []
        for ob, lam in zip(self.obstacles, self.multipliers, strict=True):
            q = x[self.n + ob.qi]
            g, valid, dgdp, dgdq, d2q, d2pq, d2pp = ob.evaluate(p, q)
            k = self.k_node
            trial = lam - k * g
            act = valid & (trial > 0)
            f = np.where(act, trial, 0.0)  # contact force on each node [N]
            forces.append(f)
            energy += float(np.sum(np.where(act, trial**2, 0.0) / (2 * k) - lam**2 / (2 * k)))
            if not np.any(act):
                continue
            ia = np.nonzero(act)[0]
            fa, ka = f[ia], k[ia]
            dp = dgdp[ia]
            dofs = self.rim.dofs[ia]
            qd = self.n + ob.qi
            np.add.at(grad, dofs[:, 0], -fa * dp[:, 0])
            np.add.at(grad, dofs[:, 1], -fa * dp[:, 1])
            grad[qd] += float(np.sum(-fa * dgdq[ia]))
            if want_tangent:
                # Hessian of psi(g(x)): k dg dg^T - f d2g (d2g/dp2 only for a curved obstacle)
                for a in range(2):
                    for b in range(2):
                        rows.append(dofs[:, a])
                        cols.append(dofs[:, b])
                        curved = 0.0 if d2pp is None else fa * d2pp[ia, a, b]
                        vals.append(ka * dp[:, a] * dp[:, b] - curved)
                    kpq = ka * dp[:, a] * dgdq[ia] - fa * d2pq[ia, a]
                    rows += [dofs[:, a], np.full(ia.size, qd)]
                    cols += [np.full(ia.size, qd), dofs[:, a]]
                    vals += [kpq, kpq]
                rows.append(np.array([qd]))
                cols.append(np.array([qd]))
                vals.append(np.array([np.sum(ka * dgdq[ia] ** 2 - fa * d2q[ia])]))
        corner_forces = np.zeros(len(self.corners))
        if self.corners:
            poly_idx = self.rim_order
            poly = p[poly_idx]
            k = self.k_corner
            for ci, corner in enumerate(self.corners):
                qd = self.n + corner.qi
                c, dc, d2c = corner.evaluate(float(x[qd]))
                lam_c = self.corner_multipliers[ci]
                terms = _corner_terms(poly, c, corner.radius_m)
                if corner.radius_m > 0.0:
                    lam_c = 0.0  # a rounded corner's terms are pure penalty
                for gap, kind, idx, sign in terms:
                    trial = lam_c - k * gap
                    if trial <= 0:
                        energy -= lam_c**2 / (2 * k)
                        continue
                    corner_forces[ci] += trial
                    energy += (trial**2 - lam_c**2) / (2 * k)
                    if kind == "segment":
                        nodes = [poly_idx[idx], poly_idx[(idx + 1) % poly_idx.size]]
                        z = np.concatenate((poly[idx], poly[(idx + 1) % poly_idx.size], c))
                        _, gz, hz = _with_hessian(_segment_gap_gradient, z, sign)
                    else:
                        nodes = [poly_idx[idx]]
                        z = np.concatenate((poly[idx], c))
                        _, gz, hz = _with_hessian(_vertex_distance_gradient, z, sign)
                    # chain rule from (rim nodes, corner position) to (rim dofs, q)
                    nv = 2 * len(nodes)
                    dg = np.concatenate((gz[:nv], [gz[nv:] @ dc]))
                    dofs = np.concatenate([self.rim.dofs[i] for i in nodes] + [np.array([qd])])
                    np.add.at(grad, dofs, -trial * dg)
                    if want_tangent:
                        d2g = np.empty((nv + 1, nv + 1))
                        d2g[:nv, :nv] = hz[:nv, :nv]
                        d2g[:nv, nv] = d2g[nv, :nv] = hz[:nv, nv:] @ dc
                        d2g[nv, nv] = dc @ hz[nv:, nv:] @ dc + gz[nv:] @ d2c
                        local = k * np.outer(dg, dg) - trial * d2g
                        rows.append(np.repeat(dofs, nv + 1))
                        cols.append(np.tile(dofs, nv + 1))
                        vals.append(local.ravel())
        return energy, grad, (rows, cols, vals), forces, corner_forces

    def energy(self, x: np.ndarray, load: float) -> float:
        e_el = self.body.energy(x[: self.n])
        if not math.isfinite(e_el):
            return math.inf
        e_c = self._contact(x, load, False)[0]
        e_q, _, _ = self.q_potential(x[self.n :], load)
        return e_el + e_c + e_q

    def energy_gradient(self, x: np.ndarray, load: float) -> tuple[float, np.ndarray | None]:
        e_el, g_el = self.body.energy_gradient(x[: self.n])
        if g_el is None:
            return math.inf, None
        e_c, g, _, _, _ = self._contact(x, load, False)
        e_q, g_q, _ = self.q_potential(x[self.n :], load)
        g[: self.n] += g_el
        g[self.n :] += g_q
        return e_el + e_c + e_q, g

    def evaluate(self, x: np.ndarray, load: float):
        out = self.body.evaluate(x[: self.n])
        if out is None:
            return None
        e_el, g_el, k_el = out
        e_c, g_c, (rows, cols, vals), _, _ = self._contact(x, load, True)
        e_q, g_q, h_q = self.q_potential(x[self.n :], load)
        g = g_c
        g[: self.n] += g_el
        g[self.n :] += g_q
        nt = self.ntot
        qidx = np.arange(self.n, nt)
        rr = np.concatenate(rows + [np.repeat(qidx, self.nq)]) if rows else np.repeat(qidx, self.nq)
        cc = np.concatenate(cols + [np.tile(qidx, self.nq)]) if cols else np.tile(qidx, self.nq)
        vv = np.concatenate(vals + [h_q.ravel()]) if vals else h_q.ravel()
        kc = sp.csr_matrix((vv, (rr, cc)), shape=(nt, nt))
        indptr = np.concatenate((k_el.indptr, np.full(self.nq, k_el.indptr[-1])))
        k_full = sp.csr_matrix((k_el.data, k_el.indices, indptr), shape=(nt, nt)) + kc
        return e_el + e_c + e_q, g, k_full

    def contact_forces(self, x: np.ndarray, load: float) -> tuple[list[np.ndarray], np.ndarray]:
        """Per-obstacle node forces and per-corner forces [N]."""
        out = self._contact(x, load, False)
        return out[3], out[4]

    def contact_list(self, x: np.ndarray, load: float, with_patches: bool = False,
                     carriers: list | None = None) -> tuple[np.ndarray, ...]:
        """The contacts on the body and their net force and moment about the origin.

        Returns ``(normals (k, 2), points (k, 2) [m], forces (k,) [N], net_force (2,) [N],
        net_moment [N·m])``: each loaded rim node on a jaw (its normal the gap's gradient, the
        face's on a straight jaw, the force the node's penalty force) and each loaded jaw corner
        (its normal the direction of the force it puts on the rim nodes it presses, at the
        corner's point of contact); the net force and moment sum the forces on the rim nodes
        (the hub carries their opposite at equilibrium). With ``with_patches``, a sixth array
        (k,) of each contact's pressure-patch label (:func:`envs.model.loads.holding_row`):
        on a grooved jaw the run of consecutive loaded rim nodes it belongs to (a groove's
        rounded mouth edge joins the run of a node it presses), else
        :data:`envs.model.holding.NO_PATCH`. ``carriers``, a list, gets one ``(finger, nodes,
        shares)`` a contact: its finger (0 right, 1 left) and the rim nodes its force acts on
        with their shares of it (the loaded grasp's compliance, :mod:`envs.fem.loaded`).
        """
        p = self.rim_positions(x)
        nodes, corner_forces = self.contact_forces(x, load)
        normals, points, forces, patches = [], [], [], []
        net = np.zeros(2)
        moment = 0.0
        node_patch = np.full(p.shape[0], NO_PATCH)  # the run label of each loaded grooved node
        for index, (ob, f) in enumerate(zip(self.obstacles, nodes, strict=True)):
            _, _, dgdp, *_ = ob.evaluate(p, x[self.n + ob.qi])
            act = np.flatnonzero(f > 0)
            # the obstacle pushes a node along its normal (the gap's gradient)
            vec = f[act, None] * dgdp[act]
            net += vec.sum(axis=0)
            moment += float(np.sum(p[act, 0] * vec[:, 1] - p[act, 1] * vec[:, 0]))
            normals.append(dgdp[act])
            points.append(p[act])
            forces.append(f[act])
            if carriers is not None:
                carriers.extend((ob.qi, np.array([node]), np.ones(1)) for node in act)
            labels = np.full(act.size, NO_PATCH)
            if getattr(ob, "grooved", False) and self.rim_order is not None:
                labels = _run_labels(f > 0, self.rim_order, index)[act]
                node_patch[act] = labels
            patches.append(labels)
        if self.corners:
            poly = p[self.rim_order]
            k = self.k_corner
            for corner, lam_c, f in zip(self.corners, self.corner_multipliers, corner_forces,
                                        strict=True):
                if not f > 0:
                    continue
                c = corner.evaluate(float(x[self.n + corner.qi]))[0]
                lam = 0.0 if corner.radius_m > 0.0 else lam_c
                total = np.zeros(2)
                pressed = []  # the rim nodes (rim indices) this corner pushes
                pushes = []  # the size of its push on each
                for gap, kind, idx, sign in _corner_terms(poly, c, corner.radius_m):
                    trial = lam - k * gap
                    if not trial > 0:
                        continue
                    if kind == "segment":
                        ends = [idx, (idx + 1) % poly.shape[0]]
                        _, gz = _segment_gap_gradient(np.concatenate((poly[ends[0]],
                                                                      poly[ends[1]], c)))
                    else:
                        ends = [idx]
                        _, gz = _vertex_distance_gradient(np.concatenate((poly[idx], c)))
                    gz = sign * np.real(gz[: 2 * len(ends)]).reshape(-1, 2)
                    vec = trial * gz  # the force on each rim node the corner presses
                    pressed.extend(int(self.rim_order[e]) for e in ends)
                    pushes.extend(np.linalg.norm(vec, axis=1))
                    net += vec.sum(axis=0)
                    moment += float(np.sum(poly[ends, 0] * vec[:, 1] - poly[ends, 1] * vec[:, 0]))
                    total += vec.sum(axis=0)
                size = float(np.linalg.norm(total))
                normals.append((total / size)[None, :])
                # a rounded corner touches the rim its radius from its centre, along the push
                points.append((c + corner.radius_m * total / size)[None, :])
                forces.append(np.array([size]))
                if carriers is not None:
                    carriers.append((corner.qi, np.array(pressed), np.array(pushes)
                                     / float(np.sum(pushes))))
                patches.append(np.array([_corner_patch(corner, pressed, node_patch,
                                                       len(self.obstacles) * p.shape[0]
                                                       + len(patches))]))
        out = (np.concatenate(normals) if normals else np.zeros((0, 2)),
               np.concatenate(points) if points else np.zeros((0, 2)),
               np.concatenate(forces) if forces else np.zeros(0), net, moment)
        if with_patches:
            return (*out, np.concatenate(patches).astype(np.int64) if patches
                    else np.zeros(0, dtype=np.int64))
        return out

    def gaps(self, x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        p = self.rim_positions(x)
        out = []
        for ob in self.obstacles:
            g, valid, *_ = ob.evaluate(p, x[self.n + ob.qi])
            out.append((g, valid))
        return out

    def update_multipliers(self, x: np.ndarray, load: float) -> None:
        nodes, corners = self.contact_forces(x, load)
        self.multipliers = [f.copy() for f in nodes]
        self.corner_multipliers = corners.copy()

    def solve(self, kff: sp.csr_matrix, rhs: np.ndarray) -> np.ndarray:
        """Sparse LU solve (SuperLU, symmetric mode).

        The fill-reducing ordering (minimum degree on ``A^T + A``) is computed at the first
        factorisation and reused afterwards (the sparsity pattern only changes by the few
        contact couplings), which saves the ordering time of every Newton step.
        """
        opts = {"SymmetricMode": True}
        if self._order is None or self._order.size != kff.shape[0]:
            lu = spla.splu(kff.tocsc(), permc_spec="MMD_AT_PLUS_A", options=opts)
            self._order = np.argsort(lu.perm_c)
            return lu.solve(rhs)
        o = self._order
        lu = spla.splu(kff[o][:, o].tocsc(), permc_spec="NATURAL", options=opts)
        out = np.empty_like(rhs)
        out[o] = lu.solve(rhs[o])
        return out

    def penetration(self, x: np.ndarray) -> float:
        """Largest penetration [m] of a rim node into a face or of a jaw corner into the rim."""
        p = self.rim_positions(x)
        worst = 0.0
        for ob in self.obstacles:
            g, valid, *_ = ob.evaluate(p, x[self.n + ob.qi])
            if np.any(valid):
                worst = max(worst, float(np.max(-g[valid])))
        if self.corners:
            poly = p[self.rim_order]
            for corner in self.corners:
                c = corner.evaluate(float(x[self.n + corner.qi]))[0]
                worst = max(worst, corner.radius_m - _corner_feature(poly, c)[0])
        return worst

    def rounded_corner_penetration(self, x: np.ndarray) -> float:
        """Largest penetration [m] of a rounded jaw corner (a groove's mouth edge) into the rim,
        0 where there is none."""
        worst = 0.0
        poly = self.rim_positions(x)[self.rim_order] if self.corners else None
        for corner in self.corners:
            if corner.radius_m > 0.0:
                c = corner.evaluate(float(x[self.n + corner.qi]))[0]
                worst = max(worst, corner.radius_m - _corner_feature(poly, c)[0])
        return worst

    def penetration_cap(self, x: np.ndarray) -> float:
        """Largest penetration a line-search trial point may have (anti-tunnelling guard)."""
        return max(self.pen_cap_m, 2.0 * self.penetration(x))

    def residual_ratio(self, g: np.ndarray) -> float:
        """Largest free residual (forces; generalised forces / ``q_scale``) over the tolerance."""
        gf = g[self.free]
        nu = self.free.size - self.nq
        r_u = float(np.max(np.abs(gf[:nu]), initial=0.0))
        r_q = float(np.max(np.abs(gf[nu:]) / self.q_scale, initial=0.0))
        return max(r_u, r_q) / self.force_tol_n

    def converged(self, g: np.ndarray) -> bool:
        return self.residual_ratio(g) <= 1.0


def _run_labels(loaded: np.ndarray, order: np.ndarray, obstacle: int) -> np.ndarray:
    """Pressure-patch label of each rim node (rim indices) for one obstacle: the run of
    consecutive loaded nodes along the rim (``order``: the rim counter-clockwise) that the node
    belongs to, named ``obstacle * m + first`` by the run's first node's place in ``order``;
    :data:`envs.model.holding.NO_PATCH` for a free node."""
    m = order.size
    on = loaded[order]
    labels = np.full(loaded.size, NO_PATCH)
    if not on.any():
        return labels
    if on.all():
        labels[order] = obstacle * m
        return labels
    start = int(np.argmin(on))  # a free node: no run wraps round the walk's start
    first = -1
    for k in range(1, m + 1):
        place = (start + k) % m
        if on[place]:
            if first < 0:
                first = place
            labels[order[place]] = obstacle * m + first
        else:
            first = -1
    return labels


def _corner_patch(corner, pressed: list[int], node_patch: np.ndarray, own: int) -> int:
    """Pressure-patch label of a loaded jaw corner: a groove's rounded mouth edge joins the run
    of a grooved node among those it presses; the tips (sharp, radius 0) and a mouth edge
    pressing no loaded node are patches of their own (``own``), the tips by the flat-face rule
    (:data:`envs.model.holding.NO_PATCH`)."""
    if not corner.radius_m > 0.0:
        return NO_PATCH
    for node in pressed:
        if node_patch[node] != NO_PATCH:
            return int(node_patch[node])
    return own
