"""Pinned answers: the regression corpus of ``scripts/regression_corpus.py``.

Code that moves must not change what the solver answers. Every design row and preset case of
the corpus is recomputed and compared to 1e-9 (angles in rad, lengths in units of the radius,
strains and rewards absolute). An intended change of answers regenerates the corpus in the same
commit, which says which rows changed and why.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import envs

ROOT = Path(__file__).resolve().parents[1]
CORPUS = ROOT / "tests" / "data" / "regression_corpus.npz"
TOL = 1e-9


def _corpus_module():
    spec = importlib.util.spec_from_file_location("regression_corpus",
                                                  ROOT / "scripts" / "regression_corpus.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def corpus():
    with np.load(CORPUS) as data:
        return dict(data)


@pytest.fixture(scope="module")
def gen():
    return _corpus_module()


def test_corpus_inputs_are_reproducible(corpus, gen):
    designs, radii = gen.design_inputs()
    np.testing.assert_array_equal(designs, corpus["designs"])
    np.testing.assert_array_equal(radii, corpus["radii"])
    assert len(gen.preset_cases()) == corpus["case_n"].size


def _assert_design_rows(out, corpus, prefix, close_keys):
    """Status, convergence and contacts exactly, ``close_keys`` to TOL, against the corpus'
    ``<prefix>design_*`` rows."""
    for key in ("status", "converged", "n_contacts"):
        np.testing.assert_array_equal(out[key], corpus[f"{prefix}design_{key}"], err_msg=key)
    for key in close_keys:
        np.testing.assert_allclose(out[key], corpus[f"{prefix}design_{key}"], rtol=0, atol=TOL,
                                   err_msg=key)


def test_design_answers_unchanged(corpus, gen):
    out = gen.evaluate_corpus_designs(corpus["designs"], corpus["radii"])
    _assert_design_rows(out, corpus, "", ("jaw_angles_rad", "peak_strain", "reward"))
    # the corpus is not trivial: most valid designs converge, and some of each disk do
    assert corpus["design_converged"].sum() > 900


def test_preset_answers_unchanged(corpus, gen):
    offset_p = offset_f = 0
    for k, (name, torque, n) in enumerate(gen.preset_cases()):
        res = gen.simulate_case(name, torque, n)
        radius = envs.Scene.preset(name).disk.radius_m
        assert res.converged == bool(corpus["case_converged"][k]), (name, torque, n)
        np.testing.assert_allclose(res.jaw_angles_rad, corpus["case_jaw_angles_rad"][k],
                                   rtol=0, atol=TOL, err_msg=f"{name} {torque} {n}")
        pts = corpus["case_points_m"][offset_p : offset_p + 2 * n].reshape(n, 2)
        np.testing.assert_allclose(res.points_m, pts, rtol=0, atol=TOL * radius,
                                   err_msg=f"{name} {torque} {n}")
        face = corpus["case_face_forces_n"][offset_f : offset_f + 2 * n].reshape(2, n)
        scale = max(float(np.abs(face).max()), 1e-30)
        np.testing.assert_allclose(res.contact_forces_n, face, rtol=0, atol=1e-7 * scale,
                                   err_msg=f"{name} {torque} {n}")
        offset_p += 2 * n
        offset_f += 2 * n


def test_default_model_inputs_are_reproducible(corpus, gen):
    designs, names = gen.default_design_inputs()
    np.testing.assert_array_equal(designs, corpus["default_designs"])
    np.testing.assert_array_equal(names, corpus["default_disks"])
    assert len(gen.default_preset_cases()) == corpus["default_case_names"].size


def test_default_model_design_answers_unchanged(corpus, gen):
    out = gen.evaluate_default_designs(corpus["default_designs"], corpus["default_disks"])
    _assert_design_rows(out, corpus, "default_", ("jaw_angles_rad", "peak_strain", "reward",
                                                  "peak_compression", "contact_score",
                                                  "pin_force_n", "required_friction",
                                                  "payload_n", "grip_force_n"))
    # not trivial: nearly every design of the object-relative box is a converged grasp
    assert corpus["default_design_converged"].mean() > 0.9


def test_default_model_preset_answers_unchanged(corpus, gen):
    for k, (name, torque) in enumerate(gen.default_preset_cases()):
        res = gen.simulate_default_case(name, torque)
        radius = envs.Scene.preset(name).disk.radius_m
        where = f"{name} {torque}"
        assert res.converged == bool(corpus["default_case_converged"][k]), where
        np.testing.assert_allclose(res.jaw_angles_rad, corpus["default_case_jaw_angles_rad"][k],
                                   rtol=0, atol=TOL, err_msg=where)
        for key, got in (("points_m", res.points_m),
                         ("interior_points_m", res.interior_points_m)):
            np.testing.assert_allclose(got, corpus[f"default_case_{key}"][k], rtol=0,
                                       atol=TOL * radius, err_msg=f"{where} {key}")
        face = corpus["default_case_face_forces_n"][k]
        scale = max(float(np.abs(face).max()), 1e-30)
        np.testing.assert_allclose(res.contact_forces_n, face, rtol=0, atol=1e-7 * scale,
                                   err_msg=where)


def test_shaped_jaw_answers_unchanged(corpus, gen):
    """Random designs of the ``any`` jaw box (cradles, V-grooves, rounded grooves) with the
    default model: inputs reproducible, answers pinned."""
    designs, names = gen.jaw_design_inputs()
    np.testing.assert_array_equal(designs, corpus["jaw_designs"])
    np.testing.assert_array_equal(names, corpus["jaw_disks"])
    out = gen.evaluate_default_designs(designs, names)
    _assert_design_rows(out, corpus, "jaw_", ("jaw_angles_rad", "peak_strain", "reward",
                                              "peak_compression", "contact_score",
                                              "pin_force_n", "required_friction", "payload_n",
                                              "grip_force_n"))
    # not trivial: grooves are cut in most rows, and most of them grasp
    assert (designs[:, 6] > 0).mean() > 0.9 and corpus["jaw_design_converged"].mean() > 0.9
