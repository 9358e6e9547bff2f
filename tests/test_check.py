"""The compiled independent check (envs.check) gives the verdicts of the numpy reference
(tests/kkt_reference.py).

Solver answers on the presets and on random designs, states perturbed so that each condition
fails, float32 inputs and the parallel batch entry.
"""

import math

import numpy as np
import pytest
from matplotlib.path import Path

from envs import Scene, simulate
from envs.check import (
    CK_HALF_WIDTH,
    CK_LENGTH,
    CK_RHO,
    FAIL_FORCE,
    FAIL_GAP,
    FAIL_MOMENT,
    FAIL_NEGATIVE,
    FAIL_PENETRATION,
    FORCE_TOL,
    GAP_TOL,
    N_CK,
    N_OUT,
    OUT_FORCE_RES,
    OUT_PASSED,
    OUT_REASONS,
    KKTReport,
    check_batch,
    check_grasp,
    check_one,
    check_params,
    report_from_output,
)
from envs.evaluate import DESIGN_FIELDS
from tests.kkt_reference import kkt_check

PAPER = ("paper-r050", "paper-r070", "paper-r100")
RESIDUAL_ATOL = 1e-4 * FORCE_TOL  # the two checks differ by round-off (numpy BLAS sums against
# compiled loops: 2e-14 seen on a 4-point mesh), four orders below the tolerance they judge
LENGTH_ATOL = 1e-5 * GAP_TOL  # in units of the radius


def _inputs(scene, res):
    """The arguments of a check for a solver result."""
    return [scene, res.torque_nm, res.n_triangles, res.stiffness_rule, res.points_m.copy(),
            tuple(res.jaw_angles_rad), res.contact_forces_n.copy(),
            res.corner_edge_forces_n.copy(), res.stop_torques_nm.copy()]


def _assert_same(ref: KKTReport, new: KKTReport, radius: float, what: str) -> None:
    assert new.passed == ref.passed, f"{what}: {ref.reason!r} vs {new.reason!r}"
    assert new.reason == ref.reason, what
    for name, atol in (("force_residual_rel", RESIDUAL_ATOL),
                       ("moment_residual_rel", RESIDUAL_ATOL),
                       ("max_penetration_m", LENGTH_ATOL * radius),
                       ("max_contact_gap_m", LENGTH_ATOL * radius)):
        a, b = getattr(ref, name), getattr(new, name)
        assert b == pytest.approx(a, rel=1e-9, abs=atol, nan_ok=True), f"{what}: {name}"
    assert new.min_contact_force_n == ref.min_contact_force_n, what


def _compare(scene, res, what):
    args = _inputs(scene, res)
    ref, new = kkt_check(*args), check_grasp(*args)
    _assert_same(ref, new, scene.disk.radius_m, what)
    if not (np.any(args[6]) or np.any(args[7]) or np.any(args[8])):
        # springs only: the same operations on the same numbers, so the same bits (an unloaded
        # disk is judged against a 1e-6 strain: one ulp of a length shows at 1e-10)
        assert new.force_residual_rel == ref.force_residual_rel, what
    return ref


@pytest.fixture(scope="module")
def preset_results():
    """Solver answers on the paper and forceps presets, several torques and N."""
    out = []
    for name in (*PAPER, "forceps-a"):
        scene = Scene.preset(name)
        torques = (0.0, 0.05, 0.2, 1.0) if name in PAPER else (0.0, 1e-3, 5e-3)
        for n in (4, 8, 20, 60):
            for torque in torques:
                out.append((f"{name} N={n} T={torque}", scene, simulate(scene, torque, n,
                    element="spring")))
    # the other stiffness rule and a calibrated contour stiffness
    r070 = Scene.preset("paper-r070")
    out.append(("cst_fit", r070, simulate(r070, 0.2, 20, stiffness_rule="cst_fit",
                                          element="spring")))
    stiff = r070.with_changes(contour_stiffness_ratio=3.0)
    out.append(("contour x3", stiff, simulate(stiff, 0.5, 20, element="spring")))
    return out


@pytest.fixture(scope="module")
def design_results():
    """Solver answers for 200 random designs of the design box (valid at rest)."""
    rng = np.random.default_rng(20240611)
    bases = [Scene.preset(name) for name in PAPER]
    out = []
    # a box in metres around the paper scenes (the one DesignBounds had before it became
    # relative to the object), so that the same designs are checked as before
    low = np.array([0.05, math.radians(15.0), 0.0, 0.002, 0.0, 0.0])
    high = np.array([0.30, math.radians(75.0), 0.05, 0.03, 1.0, 0.06])
    for k, design in enumerate(low + 0.5 * (rng.uniform(-1.0, 1.0, (600, 6)) + 1) * (high - low)):
        fields = dict(zip(DESIGN_FIELDS, design, strict=True))
        torque = fields.pop("torque_nm")
        try:
            scene = bases[k % 3].with_changes(**fields)
        except ValueError:  # fingers overlap the disk at rest: not a grasp problem
            continue
        n = (4, 8, 20, 8)[k % 4]  # N = 60 is covered by the presets; it costs more here
        out.append((f"design {k} N={n}", scene, simulate(scene, torque, n, element="spring")))
        if len(out) == 200:
            break
    assert len(out) == 200
    return out


@pytest.fixture(scope="module")
def grasp():
    """A converged squeeze of paper-r070 with three face contacts on each finger."""
    scene = Scene.preset("paper-r070")
    res = simulate(scene, 0.2, 20, element="spring")
    assert res.converged and res.n_contacts == (3, 3)
    return scene, res


# --------------------------------------------------------------------------------------------
# solver answers


def test_presets_same_verdict(preset_results):
    passed = 0
    for what, scene, res in preset_results:
        ref = _compare(scene, res, what)
        # the solver's verdict includes the reference check (a fold is an equilibrium too)
        assert ref.passed == (res.converged or res.folded), what
        passed += ref.passed
    assert passed >= len(preset_results) - 5


def test_random_designs_same_verdict(design_results):
    passed = 0
    for what, scene, res in design_results:
        passed += _compare(scene, res, what).passed
    # the sample reaches every term of the check, and some answers fail it
    assert sum(bool(np.any(r.corner_edge_forces_n)) for _, _, r in design_results) > 10
    assert sum(bool(np.any(r.stop_torques_nm)) for _, _, r in design_results) > 3
    assert passed > 150


# --------------------------------------------------------------------------------------------
# states that must fail, each for its reason


def _face_frame(res, j):
    """Inward face normal of finger j (docs/model.md)."""
    th = res.jaw_angles_rad[j]
    return np.array([-math.cos(th), math.sin(th)]) if j == 0 else np.array(
        [math.cos(th), math.sin(th)])


def _check_both(scene, args):
    ref, new = kkt_check(*args), check_grasp(*args)
    _assert_same(ref, new, scene.disk.radius_m, "perturbed")
    assert not new.passed
    return new


def test_scaled_face_force_fails(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    args[6][0, np.argmax(args[6][0])] *= 1.01
    rep = _check_both(scene, args)
    assert rep.reason.startswith("force residual")
    assert rep.force_residual_rel > 1e-3


def test_point_in_finger_fails(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    i = int(np.argmax(res.contact_forces_n[0]))
    depth = 1e-5 * scene.disk.radius_m
    args[4][i] -= depth * _face_frame(res, 0)  # into the right finger, across its face
    rep = _check_both(scene, args)
    assert "penetration" in rep.reason
    assert rep.max_penetration_m == pytest.approx(depth, rel=1e-6)


def test_negative_force_fails(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    i = int(np.argmax(res.contact_forces_n[1]))
    args[6][1, i] = -args[6][1, i]
    rep = _check_both(scene, args)
    assert "negative contact force" in rep.reason
    assert rep.min_contact_force_n == -res.contact_forces_n[1, i]


def test_loaded_contact_with_gap_fails(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    i = int(np.argmax(res.contact_forces_n[1]))
    gap = 1e-6 * scene.disk.radius_m
    args[4][i] += gap * _face_frame(res, 1)  # away from the left face, still loaded
    rep = _check_both(scene, args)
    assert "loaded contact with gap" in rep.reason
    assert rep.max_contact_gap_m == pytest.approx(gap, rel=1e-6)


def test_corner_inside_contour_fails(grasp):
    scene, res = grasp
    prm = check_params(scene, res.torque_nm, 8, res.stiffness_rule)
    th = res.jaw_angles_rad[0]
    axis = np.array([math.sin(th), math.cos(th)])
    corner = (np.array([scene.gripper.joint_offset_m, 0.0]) + prm[CK_LENGTH] * axis
              + (prm[CK_HALF_WIDTH] - prm[CK_RHO]) * _face_frame(res, 0))
    # a small octagon around the face tip corner of the right finger (off centre)
    rho = prm[CK_RHO]
    ang = 2 * np.pi * np.arange(8) / 8 + 0.1
    points = corner + 3 * rho * np.column_stack([np.cos(ang), np.sin(ang)]) + 0.2 * rho
    assert Path(points).contains_point(corner)
    args = [scene, res.torque_nm, 8, res.stiffness_rule, points, res.jaw_angles_rad,
            np.zeros((2, 8)), np.zeros((2, 4, 8)), np.zeros(2)]
    rep = _check_both(scene, args)
    assert "penetration" in rep.reason
    # the corner's depth: its rounding radius plus its distance to the contour (the points
    # themselves penetrate by rho at most)
    a, b = points, np.roll(points, -1, axis=0)
    t = np.clip(np.sum((corner - a) * (b - a), axis=1) / np.sum((b - a) ** 2, axis=1), 0, 1)
    dist = np.min(np.linalg.norm(corner - (a + t[:, None] * (b - a)), axis=1))
    assert rep.max_penetration_m == pytest.approx(rho + dist, rel=1e-9)
    assert rep.max_penetration_m > 3 * rho


def test_stop_torque_with_open_jaws_fails(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    args[8][0] = 1e-3
    rep = _check_both(scene, args)
    assert rep.reason.startswith("moment residual")
    assert "loaded contact with gap" in rep.reason
    assert rep.max_contact_gap_m > 0.1 * scene.disk.radius_m  # (theta - theta_min) r


def test_nan_fails_like_the_reference(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    args[4][3, 0] = np.nan
    with np.errstate(invalid="ignore"):
        rep = _check_both(scene, args)
    assert rep.reason == f"force residual nan > {FORCE_TOL:g}"


def test_output_bits_and_report(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    args[6][0] *= -1.0  # negative forces that no longer balance: three reasons at once
    prm = check_params(scene, res.torque_nm, res.n_triangles, res.stiffness_rule)
    out = np.full(N_OUT, np.nan)
    check_one(prm, args[4], np.array(args[5]), args[6], args[7], args[8], out)
    assert out[OUT_PASSED] == 0.0
    assert int(out[OUT_REASONS]) == FAIL_FORCE | FAIL_MOMENT | FAIL_NEGATIVE
    assert not int(out[OUT_REASONS]) & (FAIL_PENETRATION | FAIL_GAP)
    rep = report_from_output(out)
    assert rep == check_grasp(*args)
    assert rep.reason.split("; ")[0] == f"force residual {out[OUT_FORCE_RES]:.2e} > 1e-08"


def test_bad_shapes_raise(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    args[7] = args[7][:, :3]
    with pytest.raises(ValueError, match=r"corner_forces_n must have shape \(2, 4, 20\)"):
        check_grasp(*args)
    b, n = 3, 20
    with pytest.raises(ValueError, match="corner"):
        check_batch(np.zeros((b, N_CK)), np.zeros((b, n, 2)), np.zeros((b, 2)),
                    np.zeros((b, 2, n)), np.zeros((b, 2, 4, n - 1)), np.zeros((b, 2)),
                    np.zeros((b, N_OUT)))
    with pytest.raises(ValueError, match="batch size"):
        check_batch(np.zeros((b, N_CK)), np.zeros((b, n, 2)), np.zeros((b, 2)),
                    np.zeros((b, 2, n)), np.zeros((b, 2, 4, n)), np.zeros((b, 2)),
                    np.zeros((b - 1, N_OUT)))


# --------------------------------------------------------------------------------------------
# dtypes and batches


def test_float32_inputs_are_converted_first(grasp):
    scene, res = grasp
    args = _inputs(scene, res)
    f32 = [*args[:4], *(np.asarray(a, dtype=np.float32) for a in args[4:])]
    f32[1] = np.float32(args[1])
    f32[5] = tuple(np.float32(a) for a in args[5])
    as64 = [*f32[:4], *(np.asarray(a, dtype=np.float64) for a in f32[4:])]
    as64[1] = float(f32[1])
    as64[5] = tuple(float(a) for a in f32[5])
    rep32, rep64 = check_grasp(*f32), check_grasp(*as64)
    assert rep32 == rep64
    _assert_same(kkt_check(*as64), rep32, scene.disk.radius_m, "float32")
    # rounding the answer to float32 spoils its equilibrium: the check must see it
    assert not rep32.passed and rep32.force_residual_rel > 1e-6


def test_batch_equals_rows(preset_results):
    rows = [(scene, res) for _, scene, res in preset_results if res.n_triangles == 20]
    assert len(rows) > 10
    prms = np.stack([check_params(s, r.torque_nm, 20, r.stiffness_rule) for s, r in rows])
    assert prms.shape == (len(rows), N_CK)
    points = np.stack([r.points_m for _, r in rows])
    angles = np.array([r.jaw_angles_rad for _, r in rows])
    face = np.stack([r.contact_forces_n for _, r in rows])
    corner = np.stack([r.corner_edge_forces_n for _, r in rows])
    stop = np.stack([r.stop_torques_nm for _, r in rows])
    face[3, 0, :] *= 1.01  # one failing row
    out = np.full((len(rows), N_OUT), np.nan)
    check_batch(prms, points, angles, face, corner, stop, out)
    for b in range(len(rows)):
        row = np.full(N_OUT, np.nan)
        check_one(prms[b], points[b], angles[b], face[b], corner[b], stop[b], row)
        np.testing.assert_array_equal(out[b], row)
    assert out[3, OUT_PASSED] == 0.0 and int(out[3, OUT_REASONS]) & FAIL_FORCE
    assert np.sum(out[:, OUT_PASSED]) == len(rows) - 1


def test_hypot_is_pythons():
    """The compiled hypot gives the bits of Python's math.hypot (which the reference uses)."""
    from envs.check import _hypot

    rng = np.random.default_rng(7)
    xy = rng.normal(size=(5000, 2)) * 10.0 ** rng.uniform(-8, 2, size=(5000, 2))
    special = [(0.0, 0.0), (-0.0, 2.0), (3.0, 4.0), (5e-324, 5e-324), (1e-310, 3e-310),
               (1e308, 1e308), (1.7e308, 1.7e308), (np.inf, np.nan), (np.nan, -np.inf),
               (np.nan, 1.0), (-np.inf, 0.0)]
    for x, y in [*xy, *special]:
        assert _hypot(x, y) == pytest.approx(math.hypot(x, y), rel=0, abs=0, nan_ok=True)


def test_layout_names_are_distinct():
    from envs import check

    ck = [v for k, v in vars(check).items() if k.startswith("CK_") and not k.startswith("CK_JAW")]
    jw = [v for k, v in vars(check).items() if k.startswith("JW_")]
    # each finger's jaw takes the JW_* slots from its CK_JAW* offset
    ck += [base + v for base in (check.CK_JAW0, check.CK_JAW1) for v in jw]
    out = [v for k, v in vars(check).items() if k.startswith("OUT_")]
    assert sorted(ck) == list(range(N_CK))
    assert sorted(out) == list(range(N_OUT))
    bits = [FAIL_FORCE, FAIL_MOMENT, FAIL_PENETRATION, FAIL_GAP, FAIL_NEGATIVE]
    assert sum(bits) == 31 and len(set(bits)) == 5
