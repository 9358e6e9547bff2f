"""Compiled row loops of the batch evaluator's metrics and reward.

Why compiled: :func:`envs.evaluate_designs` serves one-row calls (every ``GripperDesign-v2``
step) as well as batches of thousands. As numpy expressions over columns the metrics and the
reward cost ~30 small array operations each, ~60 us for one row (a fan solve takes ~65 us);
one loop over the rows costs a few microseconds at any batch size. The definitions are those
documented in :func:`envs.evaluate_designs` and :class:`envs.evaluate.RewardWeights`; this
module is their only implementation.
"""

from __future__ import annotations

import math

from numba import njit

from .model.contact_width import (
    FLAT_FACE_CURVATURE_PER_M,
    contact_indicator,
    contact_share,
    curvature_weight_n,
    hertz_arc_coefficient,
    outline_hertz_coefficient,
    outline_run_share,
    plane_strain_modulus_pa,
    relative_radius_m,
    run_curvature_per_m,
    run_share,
    segment_contact,
)
from .model.geometry import finger_axes, finger_gap_m, jaw_finger_gap
from .model.jaw import corner_centre_local
from .model.layout import G_DEPTH, N_GROOVE
from .solver.status import CHECK_FAILED

# layout of the weights vector of :func:`reward_rows` (RewardWeights.vector())
(W_CONTACT, W_CONTACT_CAP, W_DEFORM, W_DEFORM_CAP, W_MISS, W_GAP, W_INVALID, W_VIOLATION,
 W_FAIL, W_SLIP) = range(10)
N_WEIGHTS = 10


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _capped(value, cap):
    """``np.minimum(value, cap)`` of one number (NaN stays NaN)."""
    return cap if value > cap else value


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _finger_share(torque_nm, kf_nm_per_rad, rest_angle_rad, jaw_angle_rad, stop_nm):
    """One finger's share of the actuation torque that grips the object, in [0, 1]."""
    if not torque_nm > 0.0:
        return 0.0
    share = (torque_nm - kf_nm_per_rad * (rest_angle_rad - jaw_angle_rad) - stop_nm) / torque_nm
    # np.clip: NaN stays NaN
    return 0.0 if share < 0.0 else (1.0 if share > 1.0 else share)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _grip_share(torque_nm, kf_nm_per_rad, rest_angle_rad, jaw0_rad, jaw1_rad, stop0_nm,
                stop1_nm):
    """The smaller of the two fingers' grip shares (ndarray.min: NaN wins)."""
    s0 = _finger_share(torque_nm, kf_nm_per_rad, rest_angle_rad, jaw0_rad, stop0_nm)
    s1 = _finger_share(torque_nm, kf_nm_per_rad, rest_angle_rad, jaw1_rad, stop1_nm)
    return s0 if (s0 < s1 or math.isnan(s0)) else s1


@njit(cache=True, error_model="numpy", _nrt=False)
def grip_share_rows(torque_nm, kf_nm_per_rad, rest_angle_rad, jaw_angles_rad, stop_torques_nm,
                    out):
    """``out[i]``: the smaller of the two fingers' grip shares of row ``i`` (see
    :func:`envs.evaluate.grip_share`)."""
    for i in range(out.shape[0]):
        out[i] = _grip_share(torque_nm[i], kf_nm_per_rad[i], rest_angle_rad[i],
                             jaw_angles_rad[i, 0], jaw_angles_rad[i, 1],
                             stop_torques_nm[i, 0], stop_torques_nm[i, 1])


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _point_indicator(points_m, forces_n, i, j, angle_rad, joint_offset_m, length_m, width_m,
                     spacing_m, thickness_m, e_star_pa):
    """:func:`~envs.model.contact_width.contact_indicator` of contour point ``i`` against the
    face of finger ``j`` (a pressed point's gap is 0: the solver holds it on the face)."""
    force = forces_n[i]
    gap = 0.0 if force > 0.0 else finger_gap_m(points_m[i, 0], points_m[i, 1], j, angle_rad,
                                               joint_offset_m, length_m, width_m)
    return contact_indicator(force, spacing_m * thickness_m, spacing_m, gap, e_star_pa)


@njit(cache=True, error_model="numpy", _nrt=False)
def face_extent_share(points_m, forces_n, j, angle_rad, joint_offset_m, length_m, width_m,
                      radius_m, thickness_m, e_star_pa):
    """Share of a contour of ``N`` evenly spaced points in contact with the face of finger
    ``j``, interpolated between points (:func:`envs.model.contact_width.contact_arc_share`
    without its arrays: each point stands for ``1 / N`` of the contour, an arc ``2 pi r / N``).

    Parameters
    ----------
    points_m
        The deformed contour points, counter-clockwise, (N, 2) [m].
    forces_n
        The face's normal force on each point, (N,) [N].
    j, angle_rad, joint_offset_m, length_m, width_m
        Finger ``j`` (0 right, 1 left), its angle [rad] and the gripper's ``d_3``, ``l``,
        ``w`` [m] (the gaps of the free points to its bar).
    radius_m, thickness_m, e_star_pa
        The disk's radius and thickness [m] and plane-strain modulus [Pa].
    """
    n = points_m.shape[0]
    spacing = 2.0 * math.pi * radius_m / n
    first = _point_indicator(points_m, forces_n, 0, j, angle_rad, joint_offset_m, length_m,
                             width_m, spacing, thickness_m, e_star_pa)
    here = first
    total = 0.0
    for i in range(n):
        after = first if i == n - 1 else _point_indicator(
            points_m, forces_n, i + 1, j, angle_rad, joint_offset_m, length_m, width_m,
            spacing, thickness_m, e_star_pa)
        total += segment_contact(here, after)
        here = after
    return total / n


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _edge_foot(points_m, k, x_m, y_m):
    """Where the point ``(x_m, y_m)`` projects onto contour edge ``k -> k + 1``, as a fraction
    of the edge from point ``k``, in [0, 1]."""
    n = points_m.shape[0]
    k1 = k + 1 if k + 1 < n else 0
    dx, dy = points_m[k1, 0] - points_m[k, 0], points_m[k1, 1] - points_m[k, 1]
    t = ((x_m - points_m[k, 0]) * dx + (y_m - points_m[k, 1]) * dy) / (dx * dx + dy * dy)
    return 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)


@njit(cache=True, error_model="numpy", _nrt=False)
def pressed_force_n(points_m, forces_n, corner_forces_n, i, j, angle_rad, joint_offset_m,
                    length_m, width_m, rounding_m, groove, base):
    """The normal force grooved finger ``j`` presses contour point ``i`` with [N]: the point's
    own contact force and its share of each rounded corner's force on the two contour edges
    beside it.

    A corner pressing an edge at ``t`` along it (from point ``k`` to ``k + 1``) loads the edge's
    ends with ``1 - t`` and ``t`` of its force (its gap's gradient shares it so), and at an end
    (``t`` 0 or 1) it is that point's touch, which the solver may give to either constraint
    (:func:`envs.solver.polish._one_constraint_per_touch`). Why: where a contact slides off the
    face over a groove's mouth edge, the point's force passes to the edge's corner at a whole
    point's force, continuously in the grasp; counted in points alone, the contact's extent and
    its Hertz cap lost that force at once (a step of 0.015 in the contact score of cradles on
    paper-r070, at R = 111.257 mm, 5 mm deep, 100 mm along the finger, 0.3 N·m).

    Parameters
    ----------
    points_m, forces_n, i, j, angle_rad, joint_offset_m, length_m, width_m
        As :func:`face_extent_share`; ``forces_n`` the face contact forces of finger ``j``.
    corner_forces_n
        Finger ``j``'s corner forces on each contour edge [N], (N_CORNERS, N) (``C_*`` of
        :mod:`envs.model.layout`).
    rounding_m, groove, base
        As :func:`grooved_face_share` (the corners' centres).
    """
    n = points_m.shape[0]
    before = i - 1 if i > 0 else n - 1
    total = forces_n[i]
    ex, ey, nx, ny = finger_axes(j, math.sin(angle_rad), math.cos(angle_rad))
    jx = joint_offset_m if j == 0 else -joint_offset_m
    for c in range(corner_forces_n.shape[0]):
        if not (corner_forces_n[c, before] > 0.0 or corner_forces_n[c, i] > 0.0):
            continue
        s, m = corner_centre_local(c, length_m, 0.5 * width_m, rounding_m, groove, base)
        cx, cy = jx + s * ex + m * nx, s * ey + m * ny
        if corner_forces_n[c, before] > 0.0:
            total += corner_forces_n[c, before] * _edge_foot(points_m, before, cx, cy)
        if corner_forces_n[c, i] > 0.0:
            total += corner_forces_n[c, i] * (1.0 - _edge_foot(points_m, i, cx, cy))
    return total


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _jaw_indicator(points_m, own_force, force, i, j, angle_rad, joint_offset_m, length_m,
                   width_m, rounding_m, groove, base, spacing_m, thickness_m, e_star_pa):
    """:func:`_point_indicator` of point ``i`` pressed with ``force`` [N]
    (:func:`pressed_force_n`, of which ``own_force`` its own contact's) against a grooved
    finger (the gap to the jaw's surface, :func:`envs.model.geometry.jaw_finger_gap`) and the
    curvature of the surface nearest the point. A point pressed through a corner on an edge
    beside it keeps its gap: 0 where the corner's foot is at the point, growing as the foot
    moves along the edge away from it."""
    gap, curvature = jaw_finger_gap(points_m[i, 0], points_m[i, 1], j, angle_rad,
                                    joint_offset_m, length_m, width_m, rounding_m, groove, base)
    if own_force > 0.0:
        gap = 0.0  # the solver holds a pressed point on the surface
    return contact_indicator(force, spacing_m * thickness_m, spacing_m, gap, e_star_pa), curvature


@njit(cache=True, error_model="numpy", _nrt=False)
def grooved_face_share(points_m, forces_n, corner_forces_n, j, angle_rad, joint_offset_m,
                       length_m, width_m, rounding_m, groove, base, radius_m, thickness_m,
                       modulus_pa, poisson_ratio):
    """Share of the contour in contact with a grooved finger ``j``: the sum over its contacts
    of :func:`envs.model.contact_width.run_share`, the rule the FEM's rim applies too.

    A *contact* is a run of consecutive pressed points (a positive indicator,
    :func:`envs.model.contact_width.contact_indicator`) with the segments on either side
    interpolated as in :func:`face_extent_share`: a V-groove's two flanks are two contacts, a
    cradle's arc one. A point's force is its own contact's and its share of the rounded
    corners' forces on the edges beside it (:func:`pressed_force_n`: a mouth edge pressing the
    contour between two points). Each run's extent is capped by the Hertz width of its force on
    the jaw's curvature under it (its points' curvatures weighted by their own contacts' forces,
    so a rounded corner weighs nothing, :func:`envs.model.contact_width.run_curvature_per_m`;
    from :func:`envs.model.geometry.jaw_finger_gap`), the cap at most
    :data:`envs.model.contact_width.EDGE_CORRECTION_SPACINGS` of a spacing below the extent at
    each edge: a flank is a flat face, a cradle of radius ``R > r`` has the relative radius
    ``R r / (R - r)``, an arc that fits the disk (``R <= r``) no cap, and a disk wedged into a
    groove narrower than itself scores the extent it touches.

    Parameters
    ----------
    points_m, forces_n, j, angle_rad, joint_offset_m, length_m, width_m
        As :func:`face_extent_share`.
    corner_forces_n
        Finger ``j``'s corner forces on the contour edges [N], (N_CORNERS, N).
    rounding_m, groove, base
        The corner radius ``rho`` [m] and the finger's groove packed in metres at
        ``groove[base:]`` (:func:`envs.model.jaw.pack_groove` with unit 1).
    radius_m, thickness_m, modulus_pa, poisson_ratio
        The disk's ``r``, ``t`` [m], modulus ``E`` [Pa] and ``nu`` (the material's, as for
        :func:`psm_metrics_rows`).
    """
    return _grooved_share(points_m, forces_n, corner_forces_n, j, angle_rad, joint_offset_m,
                          length_m, width_m, rounding_m, groove, base, radius_m, thickness_m,
                          modulus_pa, poisson_ratio, 0.0, forces_n)


@njit(cache=True, error_model="numpy", _nrt=False)
def _grooved_share(points_m, forces_n, corner_forces_n, j, angle_rad, joint_offset_m,
                   length_m, width_m, rounding_m, groove, base, radius_m, thickness_m,
                   modulus_pa, poisson_ratio, perimeter_m, curvature_per_m):
    """:func:`grooved_face_share`; with ``perimeter_m > 0`` of an outline of that perimeter
    [m], the contour points spaced evenly along it and ``curvature_per_m`` (N,) their rest
    curvatures [1/m]: each run capped on the outline's own curvature under it, its points'
    weighted by their own contacts' forces
    (:func:`envs.model.contact_width.outline_run_share`); ``perimeter_m = 0`` reads the disk
    of ``radius_m`` (``curvature_per_m`` unread)."""
    n = points_m.shape[0]
    outline = perimeter_m > 0.0
    spacing = perimeter_m / n if outline else 2.0 * math.pi * radius_m / n
    e_star = plane_strain_modulus_pa(modulus_pa, poisson_ratio)
    # a free point to start from, so that no run wraps round the scan's ends
    start = -1
    for i in range(n):
        phi, _ = _jaw_indicator(points_m, forces_n[i], pressed_force_n(
            points_m, forces_n, corner_forces_n, i, j, angle_rad, joint_offset_m, length_m,
            width_m, rounding_m, groove, base), i, j, angle_rad, joint_offset_m, length_m,
            width_m, rounding_m, groove, base, spacing, thickness_m, e_star)
        if not phi > 0.0:
            start = i
            break
    if start < 0:
        # every point pressed: one contact round the whole contour, without edges
        total = weighted = weight = 0.0
        own = own_weight = 0.0
        for i in range(n):
            force = pressed_force_n(points_m, forces_n, corner_forces_n, i, j, angle_rad,
                                    joint_offset_m, length_m, width_m, rounding_m, groove, base)
            _, curvature = _jaw_indicator(points_m, forces_n[i], force, i, j, angle_rad,
                                          joint_offset_m, length_m, width_m, rounding_m, groove,
                                          base, spacing, thickness_m, e_star)
            total += force
            w = curvature_weight_n(forces_n[i], curvature)
            weighted += w * curvature
            weight += w
            if outline:
                own += forces_n[i] * curvature_per_m[i]
                own_weight += forces_n[i]
        if outline:
            return outline_run_share(1.0, total, run_curvature_per_m(weighted, weight), 0.0,
                                     _object_curvature(own, own_weight, curvature_per_m),
                                     perimeter_m, thickness_m, modulus_pa, poisson_ratio)
        return run_share(1.0, total, run_curvature_per_m(weighted, weight), 0.0, radius_m,
                         thickness_m, modulus_pa, poisson_ratio)
    share = 0.0
    force_before = pressed_force_n(points_m, forces_n, corner_forces_n, start, j, angle_rad,
                                   joint_offset_m, length_m, width_m, rounding_m, groove, base)
    before, _ = _jaw_indicator(points_m, forces_n[start], force_before, start, j, angle_rad,
                               joint_offset_m, length_m, width_m, rounding_m, groove, base,
                               spacing, thickness_m, e_star)
    extent = force = weighted = weight = 0.0
    own = own_weight = 0.0
    for k in range(1, n + 1):
        i = (start + k) % n
        pressed = pressed_force_n(points_m, forces_n, corner_forces_n, i, j, angle_rad,
                                  joint_offset_m, length_m, width_m, rounding_m, groove, base)
        here, curvature = _jaw_indicator(points_m, forces_n[i], pressed, i, j, angle_rad,
                                         joint_offset_m, length_m, width_m, rounding_m, groove,
                                         base, spacing, thickness_m, e_star)
        # the segment before point i belongs to the run of its pressed end(s)
        extent += segment_contact(before, here) / n
        if here > 0.0:
            force += pressed
            # weighted by the point's own contact: a corner's share presses through a
            # rounded, convex edge, which does not make the jaw under the run flatter
            w = curvature_weight_n(forces_n[i], curvature)
            weighted += w * curvature
            weight += w
            if outline:
                own += forces_n[i] * curvature_per_m[i]
                own_weight += forces_n[i]
        elif before > 0.0:
            # the run ends on this free point; its two edges lie in segments 1 / n long
            if outline:
                share += outline_run_share(
                    extent, force, run_curvature_per_m(weighted, weight), 2.0 / n,
                    _object_curvature(own, own_weight, curvature_per_m), perimeter_m,
                    thickness_m, modulus_pa, poisson_ratio)
            else:
                share += run_share(extent, force, run_curvature_per_m(weighted, weight),
                                   2.0 / n, radius_m, thickness_m, modulus_pa, poisson_ratio)
            extent = force = weighted = weight = 0.0
            own = own_weight = 0.0
        else:
            extent = 0.0
        before = here
    return share


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _object_curvature(weighted_sum, weight_sum, curvature_per_m):
    """An outline's curvature under a contact [1/m]: its pressed points' rest curvatures
    weighted by their own forces (``weighted_sum / weight_sum``); where no point carries a
    force of its own (a contact through a corner only), the largest on the contour (the
    narrowest Hertz cap: a conservative width)."""
    if weight_sum > 0.0:
        return weighted_sum / weight_sum
    big = 0.0
    for i in range(curvature_per_m.shape[0]):
        big = max(big, curvature_per_m[i])
    return big


@njit(cache=True, error_model="numpy", _nrt=False)
def _outline_face_share(points_m, forces_n, j, angle_rad, joint_offset_m, length_m, width_m,
                        perimeter_m, curvature_per_m, thickness_m, modulus_pa, poisson_ratio,
                        total_n):
    """An outline's share of the perimeter in contact with the straight face of finger ``j``:
    the interpolated extent (:func:`face_extent_share`, the points spaced evenly along the
    perimeter) at most the Hertz width of the face force ``total_n`` on the outline's own
    curvature under the contact (:func:`_object_curvature`)."""
    e_star = plane_strain_modulus_pa(modulus_pa, poisson_ratio)
    extent = face_extent_share(points_m, forces_n, j, angle_rad, joint_offset_m, length_m,
                               width_m, perimeter_m / (2.0 * math.pi), thickness_m, e_star)
    own = own_weight = 0.0
    for i in range(forces_n.shape[0]):
        if forces_n[i] > 0.0:
            own += forces_n[i] * curvature_per_m[i]
            own_weight += forces_n[i]
    k = outline_hertz_coefficient(_object_curvature(own, own_weight, curvature_per_m),
                                  FLAT_FACE_CURVATURE_PER_M, perimeter_m, thickness_m,
                                  modulus_pa, poisson_ratio)
    return contact_share(extent, total_n, k)


@njit(cache=True, error_model="numpy", _nrt=False)
def psm_metrics_rows(rows, n_points, status_in, converged_in, iterations_in, stable_in,
                     jaw_angles_rad, points_m, face_forces_n, corner_forces_n, corner_totals_n,
                     stop_torques_nm,
                     peak_strain, peak_log_strain, max_displacement_ratio, peak_compression,
                     finger_length_m, joint_offset_m, finger_width_m, radius_m, thickness_m,
                     youngs_modulus_pa, poisson_ratio, material_scale, torque_nm,
                     kf_nm_per_rad, rest_angle_rad, grooves_m, rounding_m, perimeter_m,
                     curvature_per_m, status, converged,
                     iterations, stable, jaw_out, n_contacts, touching, total_force_n,
                     contact_score, grip_share, peak_out, peak_log_out, displacement_out,
                     compression_out):
    """Write the point-spring metrics of solved rows ``rows`` (group order ``g``) into the
    output columns.

    A row counts as converged when the solver says so and its float metrics are finite
    (otherwise ``CHECK_FAILED``); failed rows keep their zeros. Contacts are the points with a
    positive face force, a finger touches with a face contact or a corner force, and the
    contact score is ``grip_share`` times the two faces'
    :func:`~envs.model.contact_width.contact_share`: the contact's extent interpolated between
    the contour points (:func:`face_extent_share`), at most the Hertz width
    (:func:`envs.model.contact_width.hertz_arc_coefficient`, flat faces). Both take the
    object's modulus, ``material_scale`` times E: the disk's own scale, not a member's
    discretization scale (which the solve's stiffness carries, and which is not part of the
    material). A grooved finger's share is :func:`grooved_face_share`, each contact capped on
    its own with the surface's curvature where it touches; ``grooves_m`` (G, 2 N_GROOVE) holds
    each row's two grooves packed in metres (:func:`envs.model.jaw.pack_groove`, unit 1; depth
    0: straight) and ``rounding_m`` (G,) the corner radius they were packed with. A row whose
    object is an outline has its perimeter ``perimeter_m[g] > 0`` [m] (0: a disk) and its
    contour points' rest curvatures ``curvature_per_m[g]`` (N,) [1/m]: its contour points
    are spaced evenly along the perimeter, and each face's Hertz cap takes the outline's own
    curvature under the contact, its pressed points' weighted by their forces
    (:func:`envs.model.contact_width.outline_hertz_coefficient`).
    """
    for g in range(rows.shape[0]):
        r = rows[g]
        finite = (math.isfinite(peak_strain[g]) and math.isfinite(peak_log_strain[g])
                  and math.isfinite(max_displacement_ratio[g])
                  and math.isfinite(peak_compression[g]))
        shares = 0.0
        modulus = material_scale[g] * youngs_modulus_pa[g]
        e_star = plane_strain_modulus_pa(modulus, poisson_ratio[g])
        hertz_k = hertz_arc_coefficient(
            radius_m[g], thickness_m[g], modulus, poisson_ratio[g],
            relative_radius_m(radius_m[g], FLAT_FACE_CURVATURE_PER_M))
        for j in range(2):
            corner = 0.0
            for k in range(corner_totals_n.shape[2]):
                corner += corner_totals_n[g, j, k]
            total = 0.0
            cnt = 0
            for p in range(face_forces_n.shape[2]):
                f = face_forces_n[g, j, p]
                total += f
                if f > 0.0:
                    cnt += 1
            base = N_GROOVE * j
            if grooves_m[g, base + G_DEPTH] > 0.0:
                shares += _grooved_share(
                    points_m[g], face_forces_n[g, j], corner_forces_n[g, j], j,
                    jaw_angles_rad[g, j],
                    joint_offset_m[g], finger_length_m[g], finger_width_m[g], rounding_m[g],
                    grooves_m[g], base, radius_m[g], thickness_m[g], modulus, poisson_ratio[g],
                    perimeter_m[g], curvature_per_m[g])
            elif perimeter_m[g] > 0.0:
                shares += _outline_face_share(
                    points_m[g], face_forces_n[g, j], j, jaw_angles_rad[g, j],
                    joint_offset_m[g], finger_length_m[g], finger_width_m[g], perimeter_m[g],
                    curvature_per_m[g], thickness_m[g], modulus, poisson_ratio[g], total)
            else:
                extent = face_extent_share(points_m[g], face_forces_n[g, j], j,
                                           jaw_angles_rad[g, j], joint_offset_m[g],
                                           finger_length_m[g], finger_width_m[g], radius_m[g],
                                           thickness_m[g], e_star)
                shares += contact_share(extent, total, hertz_k)
            total += corner
            finite = finite and math.isfinite(jaw_angles_rad[g, j]) and math.isfinite(total)
            # written for every row; a failed row's are zeroed below
            n_contacts[r, j] = cnt
            touching[r, j] = cnt > 0 or corner > 0.0
            total_force_n[r, j] = total
        ok = converged_in[g] and finite
        status[r] = CHECK_FAILED if (converged_in[g] and not finite) else status_in[g]
        iterations[r] = iterations_in[g]
        stable[r] = stable_in[g]
        converged[r] = ok
        if not ok:
            for j in range(2):
                n_contacts[r, j] = 0
                touching[r, j] = False
                total_force_n[r, j] = 0.0
            continue
        share = _grip_share(torque_nm[g], kf_nm_per_rad[g], rest_angle_rad[g],
                            jaw_angles_rad[g, 0], jaw_angles_rad[g, 1], stop_torques_nm[g, 0],
                            stop_torques_nm[g, 1])
        for j in range(2):
            jaw_out[r, j] = jaw_angles_rad[g, j]
        contact_score[r] = share * shares
        grip_share[r] = share
        peak_out[r] = peak_strain[g]
        peak_log_out[r] = peak_log_strain[g]
        displacement_out[r] = max_displacement_ratio[g]
        compression_out[r] = peak_compression[g]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _bounded(x):
    """``x / (1 + x)`` in [0, 1] for x >= 0, 1 for an infinite x (and NaN)."""
    if not x < math.inf:
        return 1.0
    return x / (1.0 + x)


@njit(cache=True, error_model="numpy", _nrt=False)
def reward_rows(weights, valid, converged, contact_score, peak_compression, strain_limit,
                touching, finger_gap_m, radius_m, rest_violation, required_friction,
                friction_coefficient, reward_contact, reward_deform, penalty_slip,
                penalty_miss, penalty_gap, penalty_invalid, penalty_fail, reward):
    """The reward terms of every row (:class:`envs.evaluate.RewardWeights`; ``weights`` in
    the ``W_*`` layout), in tiers: a grasp that holds (both fingers touching, the required
    friction within the object's coefficient) within the strain limit gets the contact and
    deformation terms; one that holds but presses beyond the strain limit only a deformation
    term below every hold within it, graded by how far beyond; one
    that would slip scores below every hold, graded by how much more friction it needs; a
    converged design with a finger off the object below every grasp, graded by the fingers
    missing and the gap; a valid design whose solve failed, the failure penalty; a design
    invalid at rest, the invalid penalty graded by the normalised ``rest_violation``."""
    floor = weights[W_DEFORM] * weights[W_DEFORM_CAP]  # the worst a hold scores: -floor
    for i in range(valid.shape[0]):
        ok = converged[i]
        rc = rd = ps = pm = pg = 0.0
        if ok:
            missing = (not touching[i, 0]) + (not touching[i, 1])
            if missing:
                pm = 0.0 - (floor + weights[W_SLIP]) - weights[W_MISS] * missing
                # ndarray.max: NaN wins
                g0 = finger_gap_m[i, 0]
                g1 = finger_gap_m[i, 1]
                gap = (g0 if (g0 > g1 or math.isnan(g0)) else g1) / radius_m[i]
                pg = 0.0 - weights[W_GAP] * gap / (1.0 + gap)
            elif not required_friction[i] <= friction_coefficient[i]:  # NaN: no hold
                excess = required_friction[i] / friction_coefficient[i] - 1.0
                ps = 0.0 - floor - weights[W_SLIP] * _bounded(excess)
            else:
                ratio = peak_compression[i] / strain_limit[i]
                if ratio <= 1.0:
                    rc = weights[W_CONTACT] * _capped(contact_score[i], weights[W_CONTACT_CAP])
                    rd = 0.0 - weights[W_DEFORM] * ratio
                else:  # NaN included: beyond the strain limit, below every hold within it
                    rd = 0.0 - weights[W_DEFORM] - (floor - weights[W_DEFORM]) * _bounded(
                        ratio - 1.0)
        pi = 0.0 if valid[i] else (0.0 - weights[W_INVALID]
                                   - weights[W_VIOLATION] * rest_violation[i])
        pf = 0.0 - weights[W_FAIL] if (valid[i] and not ok) else 0.0
        reward_contact[i] = rc
        reward_deform[i] = rd
        penalty_slip[i] = ps
        penalty_miss[i] = pm
        penalty_gap[i] = pg
        penalty_invalid[i] = pi
        penalty_fail[i] = pf
        reward[i] = rc + rd + ps + pm + pg + pi + pf
