"""The paper's cases: its three disks, the calibration torque ramp and the held-out torques."""

from __future__ import annotations

#: The paper's three disks (Tables 1 and 2).
PAPER_SCENES = ("paper-r050", "paper-r070", "paper-r100")
#: Torque ramp used for the calibrations of the paper disks [N·m] (peak strain ~3 % to ~27 %).
PAPER_TORQUES_NM = tuple(round(0.05 * k, 10) for k in range(1, 11))
#: Torques not used in the calibration [N·m]: the midpoints of :data:`PAPER_TORQUES_NM` and two
#: extrapolated torques beyond its range.
HELDOUT_TORQUES_NM = tuple(round(0.025 + 0.05 * k, 10) for k in range(1, 10)) + (0.6, 0.75)
