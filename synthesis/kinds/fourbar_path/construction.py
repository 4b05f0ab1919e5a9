"""The four-bar by the textbook complex-number construction: independent of synthesis.kinematics.

Joint positions from complex numbers and an inverse cosine (law of cosines), not from
``kinematics.coupler_point`` (the closed form the NLP, ``check`` and the re-check use).  It is no rule
set: the synthetic-truth targets are sampled with it (so the truth does not come from the code that
solves for it), the bench's differential evolution evaluates its population with it (vectorised
numpy), the figures draw the linkage with it, and the tests use it as the independent oracle of the
closed form and of the rules (tests/fourbar_path_support.py).
"""

from __future__ import annotations

import numpy as np


def joint_positions(design: dict, theta, branch: int) -> dict[str, np.ndarray]:
    """Complex positions of O, A, B, O', P at crank angles ``theta`` (rad); NaN where the loop is open.

    Local frame O = 0, O' = r1: A = r2 e^{i theta}; B = O' + r4 e^{i(delta - branch gamma)} with delta the
    direction O' -> A and gamma the angle at O' of the triangle O'AB (law of cosines).  The global frame
    is the local one turned by theta0 and shifted to (x0, y0).
    """
    th = np.asarray(theta, dtype=float)
    r1, r2, r3, r4 = (design[k] for k in ("r1", "r2", "r3", "r4"))
    a = r2 * np.exp(1j * th)
    oa = a - r1
    d = np.abs(oa)
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = np.arccos((r4 * r4 + d * d - r3 * r3) / (2.0 * r4 * d))
    b = r1 + r4 * np.exp(1j * (np.angle(oa) - branch * gamma))
    p = a + (design["rcx"] + 1j * design["rcy"]) * (b - a) / r3
    if all(np.ndim(design[k]) == 0 and design[k] == 0.0 for k in ("x0", "y0", "theta0")):
        place = lambda z: z   # noqa: E731  (the local frame: the screen's normalised shapes, a fifth of its time)
    else:
        turn = np.exp(1j * np.radians(design["theta0"]))      # design values may be arrays (broadcast)
        shift = design["x0"] + 1j * np.asarray(design["y0"])
        place = lambda z: shift + turn * z   # noqa: E731
    return {"O": place(np.zeros_like(a)), "A": place(a), "B": place(b), "O'": place(r1 + 0 * a), "P": place(p)}
