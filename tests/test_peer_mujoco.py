"""MuJoCo peer benchmark (``scripts/peer_mujoco.py``): the model builds, the jaws close under
torque and stop on the disk near where the PSM stops them. Skipped without the optional
extras (``pip install -e ".[fem,mujoco]"``); the smallest mesh runs in about a second."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("skfem")

from envs import Scene, simulate  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def peer():
    spec = importlib.util.spec_from_file_location("peer_mujoco",
                                                  ROOT / "scripts" / "peer_mujoco.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["peer_mujoco"] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_mjcf_builds_with_pinned_hub(peer):
    scene = Scene.preset("paper-r070")
    xml, mesh = peer.build_mjcf(scene, 4, peer.MujocoSettings())
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.nflexvert == len(mesh.points_m)
    # two hinges plus two in-plane dofs per free vertex
    assert model.nv == 2 + 2 * (len(mesh.points_m) - len(mesh.pinned))
    r = scene.disk.radius_m
    rho = np.linalg.norm(mesh.points_m[mesh.pinned] - scene.disk.center_m, axis=1)
    assert np.all(rho <= 0.1 * r * (1 + 1e-9))
    assert np.allclose(np.linalg.norm(mesh.points_m[mesh.contour] - scene.disk.center_m,
                                      axis=1), r)


def test_jaws_close_onto_the_disk_near_the_psm(peer):
    scene = Scene.preset("paper-r070")
    settings = peer.MujocoSettings()
    xml, mesh = peer.build_mjcf(scene, 4, settings)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    torque = 0.25
    res = peer.run_to_rest(scene, model, data, mesh, torque, settings)
    th0 = scene.gripper.rest_angle_rad
    assert res["rest_reached"] and res["ok"], res["message"]
    theta_r, theta_l = res["jaw_angles_rad"]
    assert theta_r < th0 and theta_l < th0  # both jaws turned inward
    assert math.isclose(theta_r, theta_l, rel_tol=1e-3)  # mirror symmetry
    assert min(res["contour_vertices_touching"]) >= 1
    assert res["vertices_passed_through"] == 0
    assert res["max_vertex_penetration_over_r"] < 0.01
    psm = simulate(scene, torque, 20, element="spring")
    assert psm.converged
    psm_closing = th0 - float(np.mean(psm.jaw_angles_rad))
    # loose band: different elasticity (plane-stress SVK membrane against springs), soft contact
    assert 0.6 < res["closing_rad"] / psm_closing < 1.5
