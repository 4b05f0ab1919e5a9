"""result.json's ``facts.dynamics`` of any driven mechanism, from its inverse dynamics sampled over the crank angle.

Every kind with an input torque writes the same keys (docs/ARCHITECTURE.md "result.json"): the crank angles, the
input torque and power, the shaking force and moment, each joint's reaction with its role, each moving link's mass,
inertia, centre of mass, angle and velocities, gravity and the loads, and a summary of peaks; a kind adds its own
keys beside them.  Enough to re-check the energy balance from the file alone.  Numbers only (no kinematics): a
kind with a mechanism of its own imports it without the four-bar's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

TWO_PI = 2.0 * math.pi


def turn(samples: int) -> np.ndarray:
    """``samples`` crank angles evenly over a turn from 0 (rad)."""
    return np.linspace(0.0, TWO_PI, samples, endpoint=False)


def peaks(values: np.ndarray, crank: np.ndarray) -> dict:
    """Peak |value|, its crank angle (deg), and the RMS of a sampled quantity over a turn."""
    values = np.asarray(values, float)
    k = int(np.argmax(np.abs(values)))
    return {"peak": float(abs(values[k])), "peak_at_crank_deg": float(np.degrees(crank[k])),
            "rms": float(np.sqrt(np.mean(values ** 2)))}


def link_facts(out: dict, mass, names: tuple[str, ...], roles: tuple[str, ...],
               offset_mm: np.ndarray | None = None) -> list[dict]:
    """Each moving link: name, role, mass (kg), inertia about its centre of mass (kg m^2; ``mass`` holds four numbers
    per link: mass, centre of mass x, y, inertia), its centre of mass over the samples (mm, machine frame, ``out``'s
    plus ``offset_mm`` where the kind's frame is not the machine's), its angle (deg, unwrapped) and their velocities."""
    def com_mm(k: int) -> np.ndarray:
        com = out["com"][:, k, :].T * 1000.0
        return com if offset_mm is None else com + offset_mm

    return [{"name": name, "role": roles[k], "mass_kg": float(mass[4 * k]), "inertia_kgm2": float(mass[4 * k + 3]),
             "com_mm": com_mm(k).tolist(),
             "angle_deg": np.degrees(np.unwrap(out["angle"][k])).tolist(),
             "com_velocity_mps": out["com_velocity"][:, k, :].T.tolist(),
             "angular_velocity_radps": out["angular_velocity"][k].tolist()} for k, name in enumerate(names)]


def sampled_facts(crank: np.ndarray, out: dict, omega: float, crank_speed_rpm: float, joints: tuple[str, ...],
                  roles: tuple[str, ...], links: list[dict], gravity, loads: bool | dict, conventions: str,
                  assumption: str) -> dict[str, Any]:
    """The shared keys of ``facts.dynamics``: ``crank`` (rad) the samples; ``out`` the inverse dynamics there (torque
    N m, reactions 2 x joints x N, shaking force 2 x N, shaking moment N); ``joints`` and ``roles`` name the
    reactions' columns; ``links`` from :func:`link_facts`."""
    torque = out["torque"]
    power = torque * omega
    force = out["shaking_force"]
    magnitude = np.hypot(force[0], force[1])
    return {
        "crank_deg": np.degrees(crank).tolist(),
        "crank_speed_rpm": crank_speed_rpm,
        "input_torque_Nm": torque.tolist(),
        "power_W": power.tolist(),
        "shaking_force_N": force.T.tolist(),
        "shaking_moment_Nm": out["shaking_moment"].tolist(),
        "joints": {joints[j]: out["reactions"][:, j, :].T.tolist() for j in range(len(roles))},
        "joint_roles": dict(zip(joints, roles)),
        "links": links,
        "gravity_mps2": [float(v) for v in gravity],
        "external_loads": loads,
        "summary": {"input_torque_Nm": peaks(torque, crank), "power_W": peaks(power, crank),
                    "shaking_force_N": peaks(magnitude, crank),
                    "shaking_moment_Nm": peaks(out["shaking_moment"], crank),
                    "joints_N": {joints[j]: peaks(np.hypot(*out["reactions"][:, j, :]), crank)
                                 for j in range(len(roles))}},
        "conventions": conventions,
        "assumption": assumption,
    }
