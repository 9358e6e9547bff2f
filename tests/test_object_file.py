"""Objects from TOML files: the examples load, and every bad file is one line naming the key."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from envs.object_file import load_object
from envs.scene import SoftDisk

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "objects"
GOOD = """
[object]
radius_m = 0.012
youngs_modulus_pa = 150e3
poisson_ratio = 0.45
thickness_m = 0.024
"""


def _write(tmp_path: Path, text: str, name: str = "obj.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_example_objects_load():
    names = {p.stem: load_object(p) for p in sorted(EXAMPLES.glob("*.toml"))}
    assert set(names) >= {"cherry_tomato", "tissue_sample", "foam_disk"}
    tomato = names["cherry_tomato"]
    assert tomato.name == "cherry tomato"
    assert tomato.disk == SoftDisk(0.012, 0.0, 150e3, 0.45, 0.024, density_kg_m3=1000.0)
    assert tomato.strain_limit == 0.10 and tomato.friction_coefficient == 0.5
    assert tomato.info()["radius_m"] == 0.012
    foam = names["foam_disk"]
    scene = foam.scene()  # the [gripper] table: the paper's gripper on a foam disk
    assert scene.gripper.rest_angle_rad == pytest.approx(math.pi / 4)
    assert scene.disk.distance_m == 0.01 and scene.reachable
    # the joint spring of a gripper table without one is relative to the object
    assert scene.gripper.torsion_stiffness_nm_per_rad == pytest.approx(
        0.073 * foam.disk.torque_unit_nm / 4.9)


def test_defaults_of_the_optional_keys(tmp_path):
    spec = load_object(_write(tmp_path, GOOD, "my_fruit.toml"))
    assert spec.name == "my_fruit"
    assert spec.strain_limit is None and spec.friction_coefficient is None
    assert spec.gripper is None and spec.disk.stiffness_scale == 1.0
    with pytest.raises(ValueError, match=r"my_fruit.toml: no \[gripper\] table"):
        spec.scene()


@pytest.mark.parametrize("text,match", [
    (GOOD + "colour = 'red'\n",
     r"\[object\]: unknown key 'colour'; allowed: name, placement_tolerance_m, radius_m"),
    (GOOD.replace("radius_m = 0.012\n", ""), r"\[object\]: missing key 'radius_m'"),
    (GOOD.replace("0.012", "'0.012'"), r"\[object\]: radius_m must be a number, got '0.012'"),
    (GOOD.replace("0.012", "true"), r"\[object\]: radius_m must be a number, got True"),
    (GOOD.replace("0.012", "-0.012"), r"\[object\]: radius_m = -0.012 is outside the allowed"),
    (GOOD.replace("0.45", "0.5"), r"poisson_ratio = 0.5 is outside the allowed range \(-1, 0.5\)"),
    (GOOD.replace("0.45", "nan"), r"poisson_ratio must be finite"),
    (GOOD + "strain_limit = 1.5\n", r"strain_limit = 1.5 is outside the allowed range \(0, 1\]"),
    (GOOD + "friction_coefficient = -0.1\n", r"friction_coefficient = -0.1 is outside"),
    (GOOD + "name = ''\n", r"name must be a non-empty string"),
    (GOOD + "[grip]\nx = 1\n", r"unknown table or key 'grip'; allowed: \[object\], \[gripper\]"),
    ("[gripper]\nfinger_length_m = 0.1\n", r"missing the \[object\] table"),
    ("object = 3\n", r"object must be a table"),
    (GOOD + "radius_m = 0.01\n", r"not valid TOML"),
    (GOOD + "[gripper]\nfinger_length_m = 0.05\n", r"\[gripper\]: missing key 'joint_offset_m'"),
    (GOOD + "[gripper]\nfinger_length_m = 0.05\njoint_offset_m = 0.002\nfinger_width_m = "
     "0.004\ndistance_m = 0.01\n", r"give the rest angle once"),
    (GOOD + "[gripper]\nfinger_length_m = 0.05\njoint_offset_m = 0.002\nfinger_width_m = "
     "0.004\ndistance_m = 0.01\nrest_angle_deg = 95\n", r"rest_angle_deg = 95 is outside"),
])
def test_a_bad_file_is_one_line_naming_the_file_and_the_key(tmp_path, text, match):
    path = _write(tmp_path, text)
    with pytest.raises(ValueError, match=match) as info:
        load_object(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message


def test_a_missing_or_binary_file_is_a_value_error(tmp_path):
    with pytest.raises(ValueError, match="cannot read the object file"):
        load_object(tmp_path / "nothing.toml")
    with pytest.raises(ValueError, match="cannot read the object file"):
        load_object(tmp_path)  # a folder
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(ValueError, match="not a text"):
        load_object(binary)


def test_a_gripper_overlapping_the_object_is_named(tmp_path):
    text = GOOD + ("[gripper]\nfinger_length_m = 0.05\njoint_offset_m = 0.0\nfinger_width_m = "
                   "0.004\ndistance_m = 0.0\nrest_angle_deg = 10\n")
    spec = load_object(_write(tmp_path, text))
    with pytest.raises(ValueError, match=r"obj.toml: \[gripper\]: the fingers overlap the disk"):
        spec.scene()
