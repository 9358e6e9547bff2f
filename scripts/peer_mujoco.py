"""MuJoCo peer benchmark: the paper's r = 0.07 grasp as a MuJoCo 2-D flex, run to rest.

The disk is a ``flexcomp`` of ``dim="2"`` with in-plane vertex dofs (``dof="2d"``) on the same
structured mesh as the FEM reference (``rings`` rings, a ring on the hub's edge; the vertices
on or inside the hub of radius 0.1 r are pinned, as the FEM clamps its hub), MuJoCo's own
elasticity (``young``, ``poisson``, ``thickness`` of the scene, ``elastic2d="stretch"``). The
fingers are boxes of width w, length l and thickness t on z hinges at (+-d_3, 0) with the
torsion spring as joint ``stiffness`` (``springref`` = rest angle) and the actuation torque as a
motor (gear -1, ``ctrl = T_a``, ramped from 0). Gravity off, frictionless contact (condim 1).
Every torque is run from rest until the largest ``|qvel|`` stays below a tolerance for a
window: wall time, simulated time and steps to rest, jaw angles, contacts, peak log strain and
penetration are recorded.

Two model-form differences are reported, not hidden (see ``notes`` in the JSON):

* MuJoCo's 2-D elasticity is a plane-stress membrane with a Saint Venant-Kirchhoff law
  (checked on a square of MuJoCo 4.0.0: a uniaxial strain of 1e-4 gives sigma / eps =
  E / (1 - nu^2) = 125 kPa, the plane-stress value, not the plane-strain lambda + 2 mu =
  379 kPa of the FEM reference), and SVK softens in compression (at -10 % strain its stress is
  15 % below the linear one). Plane strain cannot be mimicked by other constants (it would
  need a membrane Poisson ratio nu / (1 - nu) = 0.82 > 0.5, which MuJoCo rejects), so the
  points are scored against both FEM references: plane strain (the speed-accuracy chart's) and
  plane stress (same 2-D assumption as MuJoCo).
* Contact is soft: the flex surface is inflated by its ``radius`` and the jaws sink into it by
  an amount set by ``solref``/``solimp``. Penetration is measured from the vertex positions
  (signed distance of every contour vertex to each jaw face), and a vertex beyond the back of a
  finger counts as a pass-through.

Writes ``out/peer_mujoco.json``. ``--quick``: the smallest mesh only (under a minute).

Usage::

    python scripts/peer_mujoco.py [--quick] [--out out]

Needs the optional extra ``pip install -e ".[fem,mujoco]"``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from speed_accuracy import REF_RINGS, SCENE, TORQUES_NM, _closing_error  # noqa: E402

from envs.accuracy import ReferenceCurve, calibrate, jsonable, psm_curve  # noqa: E402
from envs.scene import Scene  # noqa: E402

MESH_RINGS = (4, 6, 12)  # full run; --quick runs the first only
PSM_N = (20, 40)  # PSM members timed in the same run, for the time ratio
HUB_FRACTION = 0.1  # hub radius / r, as the FEM reference


@dataclass(frozen=True)
class MujocoSettings:
    """Numerical settings of the MuJoCo model (the physics is the scene's).

    Attributes
    ----------
    disk_density_kg_m3, jaw_density_kg_m3
        Densities [kg/m^3]; the answer at rest does not depend on them, the time to rest does.
    flex_radius_m
        Radius that inflates the flex triangles for collision [m] (MuJoCo needs > 0 in 2-D).
    solref_timeconst_s, solref_dampratio
        Contact ``solref`` [s, -]; MuJoCo's default is (0.02, 1).
    solimp
        Contact ``solimp`` (dmin, dmax, width [m]); MuJoCo's default (0.9, 0.95, 0.001) lets
        the jaws sink up to 0.4 mm into the finest mesh (see the contact sweep).
    timestep_per_ring_s
        Time step times rings [s] (the explicit elasticity limits the step like the element
        size): ``dt = timestep_per_ring_s / rings``.
    rayleigh_steps
        Rayleigh (stiffness) damping of the flex elasticity in time steps [-].
    jaw_damping_nms
        Hinge damping [N·m·s/rad].
    ramp_s
        Duration of the linear torque ramp from 0 to T_a [s].
    rest_velocity_tol
        Rest: max ``|qvel|`` (rad/s for the jaws, m/s for the vertices) below this ...
    rest_window_s
        ... for this long [s], after the ramp.
    max_sim_time_s
        Give up (rest not reached) after this simulated time [s].
    integrator
        MuJoCo integrator (MuJoCo 4 integrates flex elasticity explicitly with Euler; the
        implicit integrators no longer handle it).
    """

    disk_density_kg_m3: float = 1000.0
    jaw_density_kg_m3: float = 1000.0
    flex_radius_m: float = 1e-4
    solref_timeconst_s: float = 0.002
    solref_dampratio: float = 1.0
    solimp: tuple[float, float, float] = (0.99, 0.999, 1e-4)
    timestep_per_ring_s: float = 1.2e-3
    rayleigh_steps: float = 2.5
    jaw_damping_nms: float = 0.05
    ramp_s: float = 0.05
    rest_velocity_tol: float = 1e-3
    rest_window_s: float = 0.02
    max_sim_time_s: float = 3.0
    integrator: str = "Euler"

    def timestep_s(self, rings: int) -> float:
        return self.timestep_per_ring_s / rings


@dataclass(frozen=True)
class FlexMesh:
    """Rest mesh of the disk in the scene frame."""

    points_m: np.ndarray  # (n, 2)
    triangles: np.ndarray  # (m, 3), counter-clockwise
    pinned: np.ndarray  # vertex ids on or inside the hub
    contour: np.ndarray  # vertex ids on the rim
    strain_triangles: np.ndarray  # triangles whose centroid lies beyond 2 hub radii


def disk_mesh(scene: Scene, rings: int) -> FlexMesh:
    """The FEM reference's structured disk mesh (straight triangles), hub vertices pinned."""
    from envs.fem.mesh import _grasp_mesh  # the FEM's own layout, so both discretise alike

    r = scene.disk.radius_m
    hub = HUB_FRACTION * r
    mesh, _ = _grasp_mesh(r, rings, hub)
    rel = mesh.p.T.copy()
    tri = mesh.t.T.copy()
    e1, e2 = rel[tri[:, 1]] - rel[tri[:, 0]], rel[tri[:, 2]] - rel[tri[:, 0]]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]
    rho = np.linalg.norm(rel, axis=1)
    centroid_rho = np.linalg.norm(rel[tri].mean(axis=1), axis=1)
    return FlexMesh(
        points_m=rel + scene.disk.center_m,
        triangles=tri,
        pinned=np.nonzero(rho <= hub * (1 + 1e-9))[0],
        contour=np.nonzero(np.abs(rho - r) <= 1e-9 * r)[0],
        strain_triangles=np.nonzero(centroid_rho > 2 * hub)[0],
    )


def _finger_xml(scene: Scene, side: str, s: MujocoSettings) -> str:
    g, t = scene.gripper, scene.disk.thickness_m
    sign = 1.0 if side == "right" else -1.0
    # body frame: local +y along the finger axis e at the rest angle; the hinge axis is chosen
    # so that qpos = theta - theta_a0 (positive = opening) on both fingers
    axis = "0 0 -1" if sign > 0 else "0 0 1"
    solimp = " ".join(f"{v:g}" for v in s.solimp)
    return (
        f'<body name="{side}" pos="{sign * g.joint_offset_m:.12g} 0 0" '
        f'axisangle="0 0 1 {-sign * g.rest_angle_rad:.15g}">'
        f'<joint name="{side}" type="hinge" axis="{axis}" '
        f'stiffness="{g.torsion_stiffness_nm_per_rad:.12g}" springref="0" '
        f'damping="{s.jaw_damping_nms:g}"/>'
        f'<geom name="{side}" type="box" size="{g.finger_width_m / 2:.12g} '
        f'{g.finger_length_m / 2:.12g} {t / 2:.12g}" pos="0 {g.finger_length_m / 2:.12g} 0" '
        f'density="{s.jaw_density_kg_m3:g}" contype="1" conaffinity="2" condim="1" '
        f'solref="{s.solref_timeconst_s:g} {s.solref_dampratio:g}" solimp="{solimp}"/>'
        "</body>"
    )


def build_mjcf(scene: Scene, rings: int, s: MujocoSettings) -> tuple[str, FlexMesh]:
    """MJCF text of the grasp and the rest mesh of its flex."""
    mesh = disk_mesh(scene, rings)
    d = scene.disk
    mass = s.disk_density_kg_m3 * math.pi * d.radius_m**2 * d.thickness_m
    dt = s.timestep_s(rings)
    points = " ".join(f"{x:.12g} {y:.12g} 0" for x, y in mesh.points_m)
    elements = " ".join(str(int(i)) for i in mesh.triangles.ravel())
    pins = " ".join(str(int(i)) for i in mesh.pinned)
    solimp = " ".join(f"{v:g}" for v in s.solimp)
    xml = f"""<mujoco model="psm-grasp {SCENE} rings={rings}">
  <compiler angle="radian"/>
  <option timestep="{dt:.6g}" gravity="0 0 0" integrator="{s.integrator}"/>
  <worldbody>
    {_finger_xml(scene, "right", s)}
    {_finger_xml(scene, "left", s)}
    <flexcomp name="disk" type="direct" dim="2" dof="2d" radius="{s.flex_radius_m:g}"
              mass="{mass:.9g}" point="{points}" element="{elements}">
      <elasticity young="{d.youngs_modulus_pa:g}" poisson="{d.poisson_ratio:g}"
                  thickness="{d.thickness_m:g}" elastic2d="stretch"
                  damping="{s.rayleigh_steps * dt:.6g}"/>
      <contact contype="2" conaffinity="1" condim="1" selfcollide="none"
               solref="{s.solref_timeconst_s:g} {s.solref_dampratio:g}" solimp="{solimp}"/>
      <pin id="{pins}"/>
    </flexcomp>
  </worldbody>
  <actuator>
    <motor name="right" joint="right" gear="-1"/>
    <motor name="left" joint="left" gear="-1"/>
  </actuator>
</mujoco>
"""
    return xml, mesh


def face_gaps(scene: Scene, theta_rl: tuple[float, float], xy: np.ndarray) -> np.ndarray:
    """Signed gap ``n . (p - J) - w/2`` of points to the right and left gripping faces [m].

    Shape ``(2, n)``; NaN where the point is outside the finger's span ``0 <= e.(p - J) <= l``.
    """
    g = scene.gripper
    out = np.full((2, len(xy)), np.nan)
    for k, (sign, th) in enumerate(zip((1.0, -1.0), theta_rl, strict=True)):
        joint = np.array([sign * g.joint_offset_m, 0.0])
        e = np.array([sign * math.sin(th), math.cos(th)])
        n = np.array([-sign * math.cos(th), math.sin(th)])
        rel = xy - joint
        along = rel @ e
        inside = (along >= 0) & (along <= g.finger_length_m)
        out[k, inside] = rel[inside] @ n - g.finger_width_m / 2
    return out


def peak_log_strain(mesh: FlexMesh, xy: np.ndarray) -> float:
    """Largest principal |ln lambda| over the triangles beyond 2 hub radii (the FEM's measure)."""
    from envs.fem.material import _log_strain_magnitude

    tri = mesh.triangles[mesh.strain_triangles]
    x0, x = mesh.points_m, xy
    dm = np.stack((x0[tri[:, 1]] - x0[tri[:, 0]], x0[tri[:, 2]] - x0[tri[:, 0]]), axis=2)
    ds = np.stack((x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]]), axis=2)
    f = ds @ np.linalg.inv(dm)  # (m, 2, 2) deformation gradients
    det = f[:, 0, 0] * f[:, 1, 1] - f[:, 0, 1] * f[:, 1, 0]
    if np.any(det <= 0):
        return math.inf
    return float(np.max(_log_strain_magnitude(np.transpose(f, (1, 2, 0)))))


def run_to_rest(scene: Scene, model, data, mesh: FlexMesh, torque_nm: float,
                s: MujocoSettings) -> dict:
    """Reset, ramp the torque, step until rest; the state at rest and its measures."""
    import mujoco

    mujoco.mj_resetData(model, data)
    th0 = scene.gripper.rest_angle_rad
    r = scene.disk.radius_m
    w = scene.gripper.finger_width_m
    qadr = [model.joint(side).qposadr[0] for side in ("right", "left")]
    dt = model.opt.timestep
    window = max(1, round(s.rest_window_s / dt))
    bad_qacc = int(mujoco.mjtWarning.mjWARN_BADQACC)
    calm, steps, rest, reason = 0, 0, False, ""
    t0 = time.perf_counter()
    while data.time < s.max_sim_time_s:
        data.ctrl[:] = torque_nm * min(1.0, data.time / s.ramp_s)
        t_before = float(data.time)
        mujoco.mj_step(model, data)
        steps += 1
        vmax = float(np.max(np.abs(data.qvel)))
        if data.warning[bad_qacc].number > 0 or not math.isfinite(vmax):
            # MuJoCo resets an unstable state to the model's rest and carries on: stop here
            reason = f"unstable (NaN or huge acceleration at t = {t_before:.4f} s)"
            break
        calm = calm + 1 if (data.time > s.ramp_s and vmax < s.rest_velocity_tol) else 0
        if calm >= window:
            rest, reason = True, "rest"
            break
    else:
        reason = f"no rest within {s.max_sim_time_s} s simulated"
    wall = time.perf_counter() - t0
    if reason.startswith("unstable"):  # the state was reset: nothing to measure
        return {"torque_nm": torque_nm, "rest_reached": False, "ok": False, "message": reason,
                "wall_time_s": wall, "sim_time_s": t_before, "steps": steps,
                "jaw_angles_rad": (math.nan, math.nan), "closing_rad": math.nan,
                "mujoco_contacts": 0, "contour_vertices_touching": [0, 0],
                "peak_log_strain": None, "max_vertex_penetration_m": None,
                "max_vertex_penetration_over_r": None, "max_contact_penetration_m": math.nan,
                "vertices_inside_bar": 0, "vertices_passed_through": 0,
                "final_max_qvel": math.nan}

    theta = tuple(float(th0 + data.qpos[a]) for a in qadr)
    xy = np.array(data.flexvert_xpos[:, :2])
    gaps = face_gaps(scene, theta, xy)
    contour_gaps = gaps[:, mesh.contour]
    min_gap = float(np.nanmin(gaps)) if np.isfinite(gaps).any() else math.nan
    touch_tol = s.flex_radius_m + 1e-6  # within reach of the inflated flex surface
    touching = [int(np.sum(contour_gaps[k] <= touch_tol)) for k in range(2)]
    passed = int(np.sum(gaps <= -w))  # beyond the back of a finger: through it
    inside_bar = int(np.sum((gaps < 0) & (gaps > -w)))
    dists = [float(data.contact[i].dist) for i in range(data.ncon)]
    ok = rest and passed == 0 and all(map(math.isfinite, theta))
    return {
        "torque_nm": torque_nm,
        "rest_reached": rest,
        "ok": ok,
        "message": reason if passed == 0 else f"{reason}; {passed} vertices passed through a jaw",
        "wall_time_s": wall,
        "sim_time_s": float(data.time),
        "steps": steps,
        "jaw_angles_rad": theta,
        "closing_rad": th0 - float(np.mean(theta)),
        "mujoco_contacts": int(data.ncon),
        "contour_vertices_touching": touching,
        "peak_log_strain": peak_log_strain(mesh, xy) if all(map(math.isfinite, theta)) else None,
        "max_vertex_penetration_m": max(0.0, -min_gap) if math.isfinite(min_gap) else None,
        "max_vertex_penetration_over_r": max(0.0, -min_gap) / r if math.isfinite(min_gap)
        else None,
        "max_contact_penetration_m": max([0.0] + [-x for x in dists]),
        "vertices_inside_bar": inside_bar,
        "vertices_passed_through": passed,
        "final_max_qvel": float(np.max(np.abs(data.qvel))),
    }


def _num(v) -> float:
    return math.nan if v is None else float(v)


def run_mesh(scene: Scene, rings: int, torques, s: MujocoSettings) -> dict:
    """Compile the model of one mesh and run every torque from rest."""
    import mujoco

    xml, mesh = build_mjcf(scene, rings, s)
    t0 = time.perf_counter()
    try:
        model = mujoco.MjModel.from_xml_string(xml)
    except ValueError as exc:  # a failed build is a data point too
        return {"rings": rings, "build_error": str(exc), "results": []}
    data = mujoco.MjData(model)
    compile_s = time.perf_counter() - t0
    results = []
    for torque in torques:
        res = run_to_rest(scene, model, data, mesh, float(torque), s)
        results.append(res)
        print(f"  rings={rings:2d} T={torque:.3f}: {res['message']}, wall {res['wall_time_s']:.2f}"
              f" s, sim {res['sim_time_s']:.3f} s ({res['steps']} steps), closing "
              f"{res['closing_rad']:.5f} rad, penetration "
              f"{1e3 * _num(res['max_vertex_penetration_m']):.3f} mm (vertex) / "
              f"{1e3 * res['max_contact_penetration_m']:.3f} mm (contact), peak log strain "
              f"{_num(res['peak_log_strain']):.4f}")
    return {
        "rings": rings,
        "n_vertices": int(model.nflexvert),
        "n_triangles": int(model.nflexelem),
        "n_pinned": len(mesh.pinned),
        "nv": int(model.nv),
        "timestep_s": float(model.opt.timestep),
        "compile_time_s": compile_s,
        "results": results,
    }


def score(points: dict, th0: float, refs: dict[str, ReferenceCurve]) -> None:
    """Closing-angle errors (the chart's measure) and time per torque of one mesh, in place."""
    res = points["results"]
    ok = bool(res) and all(x["ok"] for x in res)
    angles = np.array([float(np.mean(x["jaw_angles_rad"])) for x in res]) if res else None
    for plane, ref in refs.items():
        if angles is None:
            rms = mx = math.nan
        else:
            rms, mx = _closing_error(th0, np.asarray(ref.jaw_angles_rad), angles)
        points[f"rms_rel_error_{plane}"] = rms
        points[f"max_rel_error_{plane}"] = mx
    points["rms_rel_error"] = points["rms_rel_error_strain"]  # the chart's reference
    points["time_per_torque_s"] = (float(np.mean([x["wall_time_s"] for x in res]))
                                   if res else math.nan)
    points["all_ok"] = ok
    points["max_vertex_penetration_m"] = max(
        (x["max_vertex_penetration_m"] or 0.0 for x in res), default=math.nan)


def fem_curve(scene: Scene, plane: str) -> tuple[ReferenceCurve, list]:
    from envs.fem import fem_grasp

    physical = scene.with_changes(stiffness_scale=1.0, contour_stiffness_ratio=1.0)
    results = fem_grasp(physical, list(TORQUES_NM), mesh_size_m=scene.disk.radius_m / REF_RINGS,
                        plane=plane)
    return ReferenceCurve.from_fem(results, source=f"fem rings={REF_RINGS} plane={plane}"), results


def psm_points(base: Scene, ref: ReferenceCurve, th0: float) -> list[dict]:
    """The PSM on the same machine in the same run (scale fitted at N = 20, as the chart's
    first stage): time per torque of a ramp (median of 3) and its error."""
    cal = calibrate(base, ref, 20, xatol=1e-3)
    scene = cal.calibrated(base)
    psm_curve(scene, TORQUES_NM, 20)  # compiled kernels loaded before timing
    out = []
    for n in PSM_N:
        runs = [psm_curve(scene, TORQUES_NM, n) for _ in range(3)]
        angles = np.asarray(runs[0].jaw_angles_rad)
        rms, mx = _closing_error(th0, np.asarray(ref.jaw_angles_rad), angles)
        out.append({"method": "newton", "n_triangles": n, "stiffness_scale": cal.scale,
                    "time_per_torque_s": float(np.median([c.time_per_solve_s for c in runs])),
                    "rms_rel_error": rms, "max_rel_error": mx,
                    "all_converged": runs[0].n_failed == 0})
        print(f"  PSM N={n}: {1e3 * out[-1]['time_per_torque_s']:.2f} ms/torque, RMS "
              f"{100 * rms:.2f} % (scale {cal.scale:.3f})")
    return out


def contact_sweep(scene: Scene, rings: int, torque: float, base: MujocoSettings) -> list[dict]:
    """What the contact settings do to penetration and angle (one mesh, the largest torque)."""
    default_imp = (0.9, 0.95, 0.001)
    variants = {
        "MuJoCo defaults: solref 0.02, solimp 0.9 0.95 0.001":
            replace(base, solref_timeconst_s=0.02, solimp=default_imp),
        "solref 0.002, default solimp": replace(base, solimp=default_imp),
        "solref 0.002, solimp 0.99 0.999 1e-4 (used)": base,
        "solref 0.0005 (dt halved), solimp used":
            replace(base, solref_timeconst_s=5e-4,
                    timestep_per_ring_s=base.timestep_per_ring_s / 2),
        "flex radius 1e-3 (10x), solimp used": replace(base, flex_radius_m=1e-3),
    }
    out = []
    for label, s in variants.items():
        print(f" contact variant: {label}")
        mesh_pts = run_mesh(scene, rings, (torque,), s)
        row = {"variant": label, "settings": asdict(s), "rings": rings}
        row.update(mesh_pts["results"][0] if mesh_pts["results"] else
                   {"build_error": mesh_pts.get("build_error")})
        out.append(row)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--quick", action="store_true",
                        help=f"smallest mesh only (rings = {MESH_RINGS[0]}), no contact sweep")
    args = parser.parse_args(argv)
    try:
        import mujoco
    except ImportError:
        print('MuJoCo is an optional extra: pip install -e ".[fem,mujoco]"', file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    base = Scene.preset(SCENE)
    th0 = base.gripper.rest_angle_rad
    refs, fem = {}, {}
    for plane in ("strain", "stress"):
        refs[plane], results = fem_curve(base, plane)
        fem[plane] = [{"torque_nm": r.torque_nm, "closing_rad": th0 - float(np.mean(
            r.jaw_angles_rad)), "peak_log_strain": r.peak_strain,
            "contact_node_counts": r.contact_node_counts} for r in results]
        print(f"FEM r/{REF_RINGS} plane {plane}: closing "
              f"{np.round(refs[plane].closing_rad(base), 5).tolist()} rad")
    settings = MujocoSettings()
    rings_list = MESH_RINGS[:1] if args.quick else MESH_RINGS
    meshes = []
    for rings in rings_list:
        pts = run_mesh(base, rings, TORQUES_NM, settings)
        score(pts, th0, refs)
        meshes.append(pts)
        print(f"MuJoCo rings={rings}: {pts['time_per_torque_s']:.2f} s/torque, RMS error "
              f"{100 * pts['rms_rel_error_strain']:.1f} % (vs plane strain), "
              f"{100 * pts['rms_rel_error_stress']:.1f} % (vs plane stress)")
    psm = psm_points(base, refs["strain"], th0)
    sweep = [] if args.quick else contact_sweep(base, MESH_RINGS[-1], max(TORQUES_NM), settings)

    best = min((m for m in meshes if m["all_ok"]), key=lambda m: m["rms_rel_error"],
               default=None)
    ratio = None
    if best is not None:
        # the cheapest PSM member at least as accurate as MuJoCo's best mesh (if any)
        matched = [p for p in psm if p["rms_rel_error"] <= best["rms_rel_error"]]
        if matched:
            fast = min(matched, key=lambda p: p["time_per_torque_s"])
            ratio = {"mujoco_rings": best["rings"], "psm_n_triangles": fast["n_triangles"],
                     "mujoco_time_per_torque_s": best["time_per_torque_s"],
                     "psm_time_per_torque_s": fast["time_per_torque_s"],
                     "mujoco_over_psm_time": best["time_per_torque_s"]
                     / fast["time_per_torque_s"],
                     "mujoco_rms_rel_error": best["rms_rel_error"],
                     "psm_rms_rel_error": fast["rms_rel_error"]}
            print(f"MuJoCo rings={best['rings']} takes {ratio['mujoco_over_psm_time']:.0f}x the "
                  f"time of PSM N={fast['n_triangles']} at equal or better PSM accuracy")
    summary = {
        "scene": SCENE,
        "torques_nm": TORQUES_NM,
        "mujoco_version": mujoco.__version__,
        "quick": args.quick,
        "settings": asdict(settings),
        "references": {k: v for k, v in refs.items()},
        "fem_reference_states": fem,
        "meshes": meshes,
        "psm": psm,
        "time_ratio_at_matched_accuracy": ratio,
        "contact_sweep": sweep,
        "notes": [
            "time per torque: wall time of mj_step from rest to rest (ramp included, model "
            "compiled once per mesh, not counted); PSM: wall time of a loading ramp per torque",
            "error: RMS over the torques of the relative closing-angle error against the FEM "
            f"r/{REF_RINGS} (rms_rel_error = plane strain, the chart's reference)",
            "MuJoCo 2-D elasticity is a plane-stress Saint Venant-Kirchhoff membrane; the FEM "
            "reference of the chart is plane-strain neo-Hookean",
            "penetration: vertex = deepest contour vertex past a jaw face (the flex surface is "
            "inflated by flex_radius_m, so a vertex stops short of the face by up to that "
            "radius minus the contact penetration); contact = deepest MuJoCo contact distance",
        ],
        "wall_time_s": time.perf_counter() - t_start,
    }
    path = out / "peer_mujoco.json"
    path.write_text(json.dumps(jsonable(summary), indent=1))
    print(f"wrote {path} in {time.perf_counter() - t_start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
