"""How much of the contour touches a face: the contact's extent, interpolated between points,
capped by the width the physics allows.

**The extent.** A contour of ``N`` points (or a FEM rim of nodes) samples the contact; counting
the pressed points (nodes) would change the measure by a whole point spacing when one point
starts or stops pressing, a jump of ``1/N`` between designs that differ by a hair. Instead each
point carries a *contact indicator* that is positive where it presses and negative where it is
free, and the contact's edge is placed where the indicator, interpolated linearly along the
contour between a pressed point and its free neighbour, crosses zero
(:func:`contact_indicator`, :func:`segment_contact`, :func:`contact_arc_share`):

- a pressed point's indicator is its pressure ``p`` [Pa] (its force over the contour length and
  thickness it stands for) turned into a length by the stiffness ``c E* / s`` of one point
  spacing ``s``: ``p s / (c E*)``, so a point pressed with a vanishing force sits at the edge;
- a free point's indicator is minus its gap ``g`` to the finger: a neighbour about to touch
  moves the edge towards itself.

Both vanish at first touch, so the extent grows continuously from 0 as a point approaches and
presses, and it is a full point spacing only where two neighbours press. ``c``
(:data:`EDGE_STIFFNESS_FACTOR`) is 1/2: the pressure of a pressed point counts as the depth it
would push into a spacing ``s`` of material twice as soft as ``E*``. On Hertz's contact of a
cylinder on a flat (a pressure ``~sqrt(b - x)`` inside the edge ``b``, a gap ``~(x - b)^{3/2}``
outside it) this places each edge up to a quarter of a point spacing beyond Hertz's (0.17 to 0.2
on average), never inside it, for any contact a spacing wide or wider
(``tests/test_contact_width.py``): an outer estimate, so that on a flat face the cap below, the
physics, sets the share of every contact resolved by a point spacing, at both fidelities alike.
The point-spring members measure a contact narrower than the FEM's by up to 4 % with ``c = 1``
(their coarse quads under the contact), which the reward (a difference of two similar terms)
turned into up to 9 % of an optimum's reward; with ``c = 1/2`` their extent lies above Hertz's
width on the grasps measured (``examples/objects``: the silicone puck and the foam disk, 40 x 2
and 96 x 6). The interpolated extent itself sets the share where the cap does not bind: at
first touch (a contact narrower than about half a spacing) and on a face that conforms to the
disk, within a quarter of a spacing at each edge.

The same definition serves both fidelities: the point-spring model's contour points (forces of
the hard constraint, gaps to the finger bar) and the FEM's rim nodes (penalty forces, for which
a pressed node's penetration is dropped: only a positive gap counts).

**The cap.** For a convex disk on a flat face the physics gives the width: a disk of radius ``r``
pressed on a rigid flat by a force ``P`` per unit thickness touches over ``2 b`` with
``b = sqrt(4 P R / (pi E*))`` (Hertz, plane strain ``E* = E / (1 - nu^2)``; the same formula as
:func:`envs.fem.hertz.hertz_line_compression`), ``R`` the *relative* radius of the two surfaces
(:func:`relative_radius_m`): ``r`` on a flat face. The share of the contour in contact with one
face is at most ``2 b / (2 pi r) = k sqrt(F)`` with ``F = P t`` and ``k`` from
:func:`hertz_arc_coefficient`; :func:`contact_share` takes the smaller of the two, so a
resolved contact scores its physical width, not a sampled one (and a first touch, narrower than
half a point spacing, the interpolated extent, which vanishes with the force). The cap is a
function of the face's geometry: a concave face (a cradle of radius ``rho >= r``) has
``R = r rho / (rho - r)``, larger than ``r``, and a face that fits the disk (``rho = r``) has no
Hertz cap at all (``R`` infinite): conforming contact extends along the whole arc that touches,
at any force, and the interpolated extent alone measures it.

**Runs on a grooved jaw.** A grooved finger's contacts are runs of neighbouring pressed points,
each scored on its own by :func:`run_share` at both fidelities: the Hertz width of the run's
force on the jaw's force-weighted curvature under it (:func:`run_curvature_per_m`), but never
more than half a spacing below the extent at each edge, so that a run over several surfaces
that conforms to the disk (a disk wedged into a groove narrower than itself) keeps its extent.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "EDGE_CORRECTION_SPACINGS",
    "EDGE_STIFFNESS_FACTOR",
    "FLAT_FACE_CURVATURE_PER_M",
    "contact_arc_share",
    "contact_indicator",
    "contact_share",
    "curvature_weight_n",
    "hertz_arc_coefficient",
    "outline_hertz_coefficient",
    "outline_run_share",
    "plane_strain_modulus_pa",
    "relative_radius_m",
    "run_curvature_per_m",
    "run_share",
    "segment_contact",
    "segment_hertz_cap",
]

#: ``c`` of the pressed points' indicator ``p s / (c E*)`` (see the module): on Hertz's profiles
#: the edge lies up to a quarter of a spacing beyond Hertz's (1 would put it a tenth beyond, 1.73
#: centre it), so that on a flat face the Hertz cap sets the share of a resolved contact.
EDGE_STIFFNESS_FACTOR = 0.5

#: The most the Hertz cap may pull each edge of a contact run back from its interpolated place,
#: in point spacings (see :func:`run_share`): twice the interpolation's overshoot on Hertz's own
#: profiles (at most a quarter spacing, ``tests/test_contact_width.py``), since the solved
#: contours' pressure profiles are not exactly Hertz's (a V's flank on the default model: 0.28).
EDGE_CORRECTION_SPACINGS = 0.5

#: Curvature of a straight gripping face [1/m] (a concave cutout: ``1 / rho`` of its arc).
FLAT_FACE_CURVATURE_PER_M = 0.0


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def plane_strain_modulus_pa(youngs_modulus_pa, poisson_ratio):
    """``E* = E / (1 - nu^2)`` [Pa] of the disk against a rigid finger (plane strain)."""
    return youngs_modulus_pa / (1.0 - poisson_ratio * poisson_ratio)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def relative_radius_m(radius_m, face_curvature_per_m):
    """Relative radius of curvature ``R`` [m] of the disk against a finger face.

    Parameters
    ----------
    radius_m
        The disk's radius ``r`` [m].
    face_curvature_per_m
        The face's curvature [1/m], positive where it is concave towards the disk (a cradle of
        radius ``rho``: ``1 / rho``), 0 for a flat face (:data:`FLAT_FACE_CURVATURE_PER_M`).

    Returns
    -------
    float
        ``1 / (1 / r - curvature)``: ``r`` on a flat face, larger on a cradle, ``inf`` where the
        face conforms to the disk or wraps it more tightly (no Hertz cap, see the module).
    """
    relative = 1.0 / radius_m - face_curvature_per_m
    return 1.0 / relative if relative > 0.0 else math.inf


@njit(cache=True, error_model="numpy", _nrt=False)
def hertz_arc_coefficient(radius_m, thickness_m, youngs_modulus_pa, poisson_ratio,
                          relative_radius_m):
    """``k`` [N^-1/2] such that ``k sqrt(F)`` is the share of the contour in contact with a face
    pressed by a force ``F`` [N] (Hertz line contact, plane strain, see the module).

    Parameters
    ----------
    radius_m, thickness_m, youngs_modulus_pa, poisson_ratio
        The disk's ``r`` [m], ``t`` [m], ``E`` [Pa] (the object's modulus: the FEM's physical
        E, the PSM's disk stiffness scale times E, without a member's discretization scale) and
        ``nu`` [-] (compiled: called per row by the design evaluator's metric loop).
    relative_radius_m
        The relative radius ``R`` [m] of the disk against the face (:func:`relative_radius_m`:
        ``r`` for a flat face, ``inf`` for a conforming one).

    Returns
    -------
    float
        ``sqrt(4 R / (pi E* t)) / (pi r)`` with ``E* = E / (1 - nu^2)``: on a flat face
        ``sqrt(4 / (pi^3 r t E*))``; ``inf`` for a conforming face (no cap).
    """
    e_star = plane_strain_modulus_pa(youngs_modulus_pa, poisson_ratio)
    if not relative_radius_m < math.inf:
        return math.inf
    return math.sqrt(4.0 * relative_radius_m / (math.pi * e_star * thickness_m)) / (
        math.pi * radius_m)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def contact_share(extent_share, face_force_n, hertz_k):
    """One face's share of the contour in contact: the interpolated extent's share
    (:func:`contact_arc_share`), at most the Hertz width ``hertz_k sqrt(F)`` of its face force
    ``F`` [N] (no cap for ``hertz_k = inf``, a conforming face)."""
    width = hertz_k * math.sqrt(face_force_n) if face_force_n > 0.0 else 0.0
    return width if width < extent_share else extent_share


@njit(cache=True, error_model="numpy", _nrt=False)
def segment_hertz_cap(force_n, face_curvature_per_m, radius_m, thickness_m, youngs_modulus_pa,
                      poisson_ratio):
    """Largest share of the contour one contact segment may cover: the Hertz width of its force.

    A contact segment is one run of neighbouring pressed points on one face (a V-groove's two
    flanks are two segments, each with its own force); the jaw's local curvature there sets the
    relative radius (:func:`relative_radius_m`): a flat face or flank caps the segment at
    ``k sqrt(F)`` with the disk's own radius, a cradle of radius ``R > r`` at the wider width of
    ``r R / (R - r)``, and a cradle that fits or wraps the disk (``R <= r``) not at all.

    Parameters
    ----------
    force_n
        The segment's normal force ``F`` [N] (the sum over its pressed points).
    face_curvature_per_m
        The jaw's curvature under the segment [1/m], positive where it is concave towards the
        disk (``1 / R`` on a cradle's arc), 0 on a flat face or flank.
    radius_m, thickness_m, youngs_modulus_pa, poisson_ratio
        The disk's ``r`` [m], ``t`` [m], ``E`` [Pa] and ``nu`` [-] (as for
        :func:`hertz_arc_coefficient`).

    Returns
    -------
    float
        ``k(R) sqrt(F)`` (:func:`hertz_arc_coefficient`), 0 for ``F <= 0``, ``inf`` where the
        face conforms (no cap).
    """
    if not force_n > 0.0:
        return 0.0
    k = hertz_arc_coefficient(radius_m, thickness_m, youngs_modulus_pa, poisson_ratio,
                              relative_radius_m(radius_m, face_curvature_per_m))
    return k * math.sqrt(force_n) if k < math.inf else math.inf


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def curvature_weight_n(force_n, curvature_per_m):
    """Weight [N] of one pressed point (rim node) in its run's curvature
    (:func:`run_curvature_per_m`): its force where the jaw under it is flat or concave, 0 on a
    rounded convex edge (a groove's mouth, rounded only so that the gap is smooth: however hard
    the disk presses it, it does not make a cradle's arc look flatter)."""
    if force_n > 0.0 and curvature_per_m >= FLAT_FACE_CURVATURE_PER_M:
        return force_n
    return 0.0


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def run_curvature_per_m(weighted_curvature_sum, weight_sum_n):
    """The jaw's curvature [1/m] under one contact run: the mean of its points' curvatures
    weighted by :func:`curvature_weight_n` (``weighted_curvature_sum = sum w_i k_i``,
    ``weight_sum_n = sum w_i``), flat where no point weighs. A weighted mean, so that it moves
    continuously as a point joins the run with a vanishing force."""
    if weight_sum_n > 0.0:
        return weighted_curvature_sum / weight_sum_n
    return FLAT_FACE_CURVATURE_PER_M


@njit(cache=True, error_model="numpy", _nrt=False)
def run_share(extent_share, force_n, curvature_per_m, edge_spacing_share, radius_m,
              thickness_m, youngs_modulus_pa, poisson_ratio):
    """One contact run's share of the contour on a grooved jaw, the same at both fidelities.

    The run's interpolated extent (the segments of its pressed points and its two interpolated
    edges), at most the Hertz width of its force on the jaw's curvature under it
    (:func:`segment_hertz_cap`), and that cap at most :data:`EDGE_CORRECTION_SPACINGS` of a
    spacing below the extent at each of its two edges: ``min(e, max(cap, e - q (s_a + s_b)))``.

    Why the floor: the cap is there to take off the extent's overshoot beyond Hertz's edge,
    which on Hertz's own profiles is at most a quarter of a spacing at each edge. A cap far
    below the extent means that the run is not a Hertz contact: a disk wedged into a groove
    narrower than itself presses its two flanks and its bottom arc as one conforming patch,
    whose extent the geometry sets (mouth to mouth), not the Hertz width of a curvature
    averaged over flanks and arc. The resolved extent is then the contact, less at most half a
    spacing at each edge, at any number of contour points or rim nodes. Continuous in the
    extent, the force and the curvature (a minimum and a maximum of continuous functions).

    Parameters
    ----------
    extent_share
        The run's interpolated extent, as a share of the contour [-].
    force_n
        The run's normal force ``F`` [N] (the sum over its pressed points).
    curvature_per_m
        The jaw's curvature under the run [1/m] (:func:`run_curvature_per_m`).
    edge_spacing_share
        The spacings at the run's two edges, summed, as a share of the contour [-] (``2 / N``
        on a contour of ``N`` evenly spaced points); 0 for a run round the whole contour.
    radius_m, thickness_m, youngs_modulus_pa, poisson_ratio
        The disk's ``r`` [m], ``t`` [m], ``E`` [Pa] and ``nu`` [-] (as for
        :func:`hertz_arc_coefficient`).
    """
    cap = segment_hertz_cap(force_n, curvature_per_m, radius_m, thickness_m, youngs_modulus_pa,
                            poisson_ratio)
    return _floored_cap(extent_share, cap, edge_spacing_share)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _floored_cap(extent_share, cap, edge_spacing_share):
    """``min(e, max(cap, e - q (s_a + s_b)))`` of :func:`run_share`."""
    floor = extent_share - EDGE_CORRECTION_SPACINGS * edge_spacing_share
    bound = cap if cap > floor else floor
    return bound if bound < extent_share else extent_share


# --- an outline's contacts: its own curvature where it touches ----------------------------


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_hertz_coefficient(object_curvature_per_m, face_curvature_per_m, perimeter_m,
                              thickness_m, youngs_modulus_pa, poisson_ratio):
    """:func:`hertz_arc_coefficient` of an outline: ``k`` [N^-1/2] such that ``k sqrt(F)`` is
    the share of its perimeter in contact with a face pressed by ``F`` [N].

    The Hertz width ``2 b``, ``b = sqrt(4 P R / (pi E*))``, with the relative radius ``R =
    1 / (kappa_o - kappa_f)`` of the outline's own curvature where it touches ``kappa_o``
    (:func:`envs.model.outline.outline_curvature`) against the face's ``kappa_f``, over the
    perimeter ``L``: ``sqrt(4 R / (pi E* t)) / (L / 2)``; on a disk (``kappa_o = 1 / r``,
    ``L = 2 pi r``) the disk's coefficient. ``inf`` where the outline is flat or concave
    there, or the face wraps it (no cap: conforming contact, as a fitted cradle).
    """
    relative = object_curvature_per_m - face_curvature_per_m
    if not relative > 0.0:
        return math.inf
    e_star = plane_strain_modulus_pa(youngs_modulus_pa, poisson_ratio)
    return math.sqrt(4.0 / (relative * math.pi * e_star * thickness_m)) / (0.5 * perimeter_m)


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_run_share(extent_share, force_n, curvature_per_m, edge_spacing_share,
                      object_curvature_per_m, perimeter_m, thickness_m, youngs_modulus_pa,
                      poisson_ratio):
    """:func:`run_share` of an outline's contact run: its Hertz cap on the outline's own
    curvature under the run ``object_curvature_per_m`` [1/m] (its pressed points' rest
    curvatures weighted by their forces) against the jaw's ``curvature_per_m``, as a share of
    the perimeter ``perimeter_m`` [m] (:func:`outline_hertz_coefficient`), with the same floor
    at each edge."""
    if not force_n > 0.0:
        cap = 0.0
    else:
        k = outline_hertz_coefficient(object_curvature_per_m, curvature_per_m, perimeter_m,
                                      thickness_m, youngs_modulus_pa, poisson_ratio)
        cap = k * math.sqrt(force_n) if k < math.inf else math.inf
    return _floored_cap(extent_share, cap, edge_spacing_share)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def contact_indicator(force_n, weight_m2, spacing_m, gap_m, e_star_pa):
    """Contact indicator [m] of one contour point (rim node) against one face: positive where
    it presses, negative where it is free, 0 at the contact's edge (see the module).

    Parameters
    ----------
    force_n
        The face's normal force on the point [N] (0 where it is free).
    weight_m2
        The contour area the point stands for [m^2]: its length share of the contour times the
        thickness (its force over it is the pressure).
    spacing_m
        The point spacing along the contour at the point [m].
    gap_m
        The point's gap to the finger [m] (a penetration, negative, counts as 0).
    e_star_pa
        The disk's plane-strain modulus ``E*`` [Pa] (:func:`plane_strain_modulus_pa`).

    Returns
    -------
    float
        ``p s / (c E*) - max(g, 0)`` with ``p = F / weight`` and ``c``
        :data:`EDGE_STIFFNESS_FACTOR`.
    """
    pressure = force_n / weight_m2 if force_n > 0.0 else 0.0
    gap = gap_m if gap_m > 0.0 else 0.0
    return pressure * spacing_m / (EDGE_STIFFNESS_FACTOR * e_star_pa) - gap


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def segment_contact(phi_a, phi_b):
    """Share in [0, 1] of the contour segment between two neighbours in contact, from their
    indicators (:func:`contact_indicator`): 1 where both press, 0 where neither does, else the
    part on the pressed side of the linear interpolation's zero."""
    if phi_a > 0.0 and phi_b > 0.0:
        return 1.0
    if not (phi_a > 0.0 or phi_b > 0.0):
        return 0.0
    pressed = phi_a if phi_a > 0.0 else phi_b
    return pressed / (abs(phi_a) + abs(phi_b))


@njit(cache=True, error_model="numpy", _nrt=False)
def contact_arc_share(phi, segment_share):
    """Share of a closed contour in contact with one face.

    Parameters
    ----------
    phi
        Contact indicators of the contour's points in their order along it, (n,)
        (:func:`contact_indicator`).
    segment_share
        Share of the contour between point ``i`` and point ``i + 1`` (the last: between the
        last point and the first), (n,); they sum to 1.

    Returns
    -------
    float
        ``sum_i segment_share[i] * segment_contact(phi[i], phi[i + 1])``.
    """
    n = phi.shape[0]
    total = 0.0
    for i in range(n):
        total += segment_share[i] * segment_contact(phi[i], phi[(i + 1) % n])
    return total
