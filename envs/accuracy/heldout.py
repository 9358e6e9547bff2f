"""Held-out FEM cases of a calibration on one paper disk (:func:`paper_heldout_cases`) and the
disks the model family's shipped scales were never fitted to (:func:`heldout_scenes`)."""

from __future__ import annotations

from collections.abc import Sequence

from ..scene import Scene
from .paper import HELDOUT_TORQUES_NM, PAPER_SCENES, PAPER_TORQUES_NM
from .reference import ReferenceCurve, fem_reference


def paper_heldout_cases(
    fitted_preset: str = "paper-r070",
    *,
    torques_nm: Sequence[float] = PAPER_TORQUES_NM,
    heldout_torques_nm: Sequence[float] = HELDOUT_TORQUES_NM,
    rings: int | None = None,
) -> dict[str, tuple[Scene, ReferenceCurve]]:
    """Held-out FEM cases of a calibration on one paper disk (for ``calibrate(heldout=...)``).

    Parameters
    ----------
    fitted_preset
        The paper preset the calibration is fitted on (one of :data:`PAPER_SCENES`).
    torques_nm
        Torque ramp of the other disks [N·m] (default: the fitting ramp
        :data:`PAPER_TORQUES_NM`, so that their FEM curves are shared with their own fits).
    heldout_torques_nm
        Torques of the fitted disk not used in the fit [N·m].
    rings
        FEM element size ``r / rings``; default :func:`envs.fem.default_mesh_size_m`.

    Returns
    -------
    dict
        ``"<preset> held-out torques"``: the fitted disk at ``heldout_torques_nm``, and
        ``"<other preset>"``: each other paper disk at ``torques_nm`` (FEM, disk-cached).
    """
    if fitted_preset not in PAPER_SCENES:
        raise ValueError(f"fitted_preset must be one of {PAPER_SCENES}, got {fitted_preset!r}")
    if rings is not None and (isinstance(rings, bool) or int(rings) != rings or rings < 2):
        raise ValueError(f"rings must be an integer >= 2, got {rings!r}")

    def ref(sc: Scene, torques) -> ReferenceCurve:
        h = None if rings is None else sc.disk.radius_m / int(rings)
        return fem_reference(sc, torques, mesh_size_m=h)

    own = Scene.preset(fitted_preset)
    cases = {f"{fitted_preset} held-out torques": (own, ref(own, heldout_torques_nm))}
    for name in PAPER_SCENES:
        if name != fitted_preset:
            other = Scene.preset(name)
            cases[name] = (other, ref(other, torques_nm))
    return cases


def heldout_scenes() -> dict[str, Scene]:
    """Disks the family's shipped scales were not fitted to (nor the hybrid scales derived on):
    other radii (rest gap ~1 mm like the presets), moduli and Poisson ratios, on the paper
    gripper. The default model is the cheapest member within tolerance on all of them
    (:func:`envs.accuracy.choose_model`)."""
    r070 = Scene.preset("paper-r070")
    return {
        "r060": r070.with_changes(radius_m=0.06, distance_m=0.0082),
        "r085": r070.with_changes(radius_m=0.085, distance_m=0.019),
        "r070-E50k": r070.with_changes(youngs_modulus_pa=50e3),
        "r070-E300k": r070.with_changes(youngs_modulus_pa=300e3),
        "r070-nu0.30": r070.with_changes(poisson_ratio=0.30),
        "r050-nu0.40": Scene.preset("paper-r050").with_changes(poisson_ratio=0.40),
    }
