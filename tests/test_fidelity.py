"""The FEM fidelity of the design evaluator: same keys and meaning as the point-spring model."""

from __future__ import annotations

import concurrent.futures

import numpy as np
import pytest

from envs.evaluate import METRIC_KEYS, DesignBounds, evaluate_designs
from envs.scene import DESIGN_FIELDS, Scene
from envs.solver.status import OK

pytest.importorskip("skfem")

FEM_RINGS = 8  # a coarse mesh keeps each FEM grasp near 0.2 s


@pytest.fixture(scope="module")
def scene() -> Scene:
    return Scene.preset("paper-r070")


@pytest.fixture(scope="module")
def designs(scene) -> np.ndarray:
    x = DesignBounds().sample(np.random.default_rng(3), 3, scene.disk)
    bad = x[0].copy()
    bad[DESIGN_FIELDS.index("finger_width_m")] = 3 * scene.disk.radius_m  # wider than the disk
    return np.vstack([bad, x])


@pytest.fixture(scope="module")
def both(scene, designs, tmp_path_factory):
    cache = tmp_path_factory.mktemp("fem-cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PSM_GRASP_CACHE", str(cache))
        fem = evaluate_designs(designs, scene.disk, fidelity="fem", fem_rings=FEM_RINGS)
        files = sorted((cache / "fem").glob("*.json"))
        again = evaluate_designs(designs, scene.disk, fidelity="fem", fem_rings=FEM_RINGS)
        files_again = sorted((cache / "fem").glob("*.json"))
    psm = evaluate_designs(designs, scene.disk)
    return psm, fem, again, files, files_again


def test_fem_fidelity_has_the_same_keys_shapes_and_dtypes(both):
    psm, fem, *_ = both
    assert set(fem) == set(METRIC_KEYS) == set(psm)
    for key, (dtype, shape) in METRIC_KEYS.items():
        assert fem[key].dtype == dtype, key
        assert fem[key].shape == (psm["reward"].shape[0], *shape), key
        if fem[key].dtype.kind == "f":
            # (an infinite required friction is an answer: no friction can carry the load)
            ok = ~np.isnan(fem[key]) if key == "required_friction" else np.isfinite(fem[key])
            assert ok.all(), key


def test_an_invalid_design_scores_the_same_at_both_fidelities(both):
    psm, fem, *_ = both
    assert not fem["valid_at_rest"][0] and not psm["valid_at_rest"][0]
    assert fem["reward"][0] == psm["reward"][0] <= -3.0


def test_fem_and_psm_agree_on_the_grasp(both):
    """The calibrated default model is within a few per cent of the FEM closing angle; the
    contact and strain measures are defined the same way, so they agree to the model's
    resolution (one contour point of 40 is 0.025 of the contour)."""
    psm, fem, *_ = both
    rows = np.arange(1, 4)
    assert fem["converged"][rows].all() and psm["converged"][rows].all()
    assert (fem["status"][rows] == OK).all()
    closing_psm = np.pi / 4 - psm["jaw_angles_rad"][rows]
    closing_fem = np.pi / 4 - fem["jaw_angles_rad"][rows]
    np.testing.assert_allclose(closing_psm, closing_fem, rtol=0.05)
    np.testing.assert_array_equal(psm["touching"][rows], fem["touching"][rows])
    np.testing.assert_allclose(psm["contact_score"][rows], fem["contact_score"][rows],
                               atol=0.06)
    np.testing.assert_allclose(psm["peak_log_strain"][rows], fem["peak_log_strain"][rows],
                               rtol=0.35, atol=1e-9)
    # the reward's deformation converges with the mesh where the peak strain does not: the
    # coarse default model measures the FEM's compression to a few per cent
    assert (fem["peak_compression"][rows] > 0.01).sum() >= 2
    np.testing.assert_allclose(psm["peak_compression"][rows], fem["peak_compression"][rows],
                               rtol=0.06, atol=1e-4)
    assert (fem["contact_score"][rows] > 0.05).sum() >= 2  # real grasps among them
    # the grip share follows from the jaw angle alone: the same formula at both fidelities
    np.testing.assert_allclose(psm["grip_share"][rows], fem["grip_share"][rows], atol=0.01)
    # the mesh of the FEM is reported instead of N
    assert (fem["n_triangles"][rows] == 6 * FEM_RINGS**2).all()


def test_fem_results_are_cached_per_design(both):
    _, fem, again, files, files_again = both
    assert len(files) == 3  # one file per design valid at rest
    assert files == files_again
    for key in METRIC_KEYS:
        np.testing.assert_array_equal(fem[key], again[key])


def test_fem_fidelity_through_an_executor_matches_in_process(scene, designs, both):
    _, fem, *_ = both
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        out = evaluate_designs(designs, scene.disk, fidelity="fem", fem_rings=FEM_RINGS,
                               executor=pool)
    for key in ("reward", "jaw_angles_rad", "contact_score", "peak_log_strain"):
        np.testing.assert_allclose(out[key], fem[key], rtol=1e-12, atol=0)


@pytest.mark.parametrize("kwargs, match", [
    ({"fidelity": "mujoco"}, "fidelity must be one of"),
    ({"fidelity": "fem", "n_triangles": 40}, "n_triangles"),
    ({"fidelity": "fem", "element": "spring"}, "element"),
    ({"fidelity": "fem", "fem_rings": 1}, "fem_rings"),
    ({"fidelity": "fem", "fem_rings": 41}, "fem_rings"),
])
def test_bad_fidelity_options_are_refused(scene, designs, kwargs, match):
    with pytest.raises(ValueError, match=match):
        evaluate_designs(designs, scene.disk, **kwargs)


def test_the_contact_width_of_the_fem_is_hertz_s():
    """The cap of the contact score is physics, not a fit: the FEM's own measure of the
    contact on each face (its extent interpolated between rim nodes, uncapped; r / 12 mesh,
    144 rim nodes) is Hertz's line-contact width of the face force on paper-r070 from light to
    firm (0.05-0.5 N·m), to 3 % and the rim's resolution (one node of the 144)."""
    from envs.fem import fem_grasp
    from envs.model.contact_width import hertz_arc_coefficient

    scene = Scene.preset("paper-r070")
    d = scene.disk
    k = hertz_arc_coefficient(d.radius_m, d.thickness_m, d.youngs_modulus_pa, d.poisson_ratio,
                              d.radius_m)
    for res in fem_grasp(scene, [0.05, 0.2, 0.5]):
        face = np.subtract(res.contact_forces_n, res.tip_forces_n)
        np.testing.assert_allclose(res.contact_fractions, k * np.sqrt(face), rtol=0.03,
                                   atol=1 / 144)


def test_compression_is_how_deep_the_contour_is_pushed_in():
    """``peak_compression`` is the largest shortening of a radius: zero for the rest mesh and
    for the rest mesh turned about the centre (which displaces every point), the depth for a
    point pushed in."""
    from envs.model.metrics import M_COMPRESSION, M_DISPLACEMENT, N_METRICS, state_metrics
    from envs.model.problem import rest_state, scaled_params
    from envs.model.rings import kernel_params

    n = 20
    prm = scaled_params(Scene.preset("paper-r070"), 0.0, n)
    x = rest_state(prm, n)[0]
    out = np.zeros(N_METRICS)
    state_metrics(x, n, kernel_params(prm, n), out)
    assert out[M_COMPRESSION] == pytest.approx(0.0, abs=1e-15)
    turned = x.copy()
    c, s_ = np.cos(0.1), np.sin(0.1)
    pts = x[: 2 * n].reshape(n, 2)
    turned[: 2 * n] = (pts @ np.array([[c, s_], [-s_, c]])).ravel()
    state_metrics(turned, n, kernel_params(prm, n), out)
    assert out[M_DISPLACEMENT] == pytest.approx(2 * np.sin(0.05), rel=1e-12)
    assert out[M_COMPRESSION] == pytest.approx(0.0, abs=1e-15)
    pushed = x.copy()
    pushed[2 * 3 : 2 * 3 + 2] *= 0.93  # point 3 moved 0.07 r towards the centre
    state_metrics(pushed, n, kernel_params(prm, n), out)
    assert out[M_COMPRESSION] == pytest.approx(0.07, rel=1e-12)
