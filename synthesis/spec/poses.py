"""The optional ``[key_poses]`` table of a transplanting kind's spec: named poses the claw must pass through.

Shared by the kinds that offer it (the rotary planetary transplanter, the four-bar planting arm; their rules:
:mod:`synthesis.constraints.poses`).  A pose asks the claw tip to be within ``tolerance`` of a point (x, y), and/or the claw's
attitude -- its direction, from +x counter-clockwise -- to be within ``attitude_tolerance`` of ``attitude``.  Each
kind's pose model adds where the pose is read (a carrier or crank angle the solver finds, one the spec prescribes,
or a named point of the kind) and says in its ``attitude`` field which line on its mechanism the claw is.
Units: mm, deg.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, model_validator

from synthesis.spec.common import StrictModel

#: the most poses a spec may name
MAX_POSES = 20


def attitude_field(description: str) -> Any:
    """A pose's claw attitude, deg in [-180, 180], absent: the pose asks none (``description``: which line on the
    kind's mechanism the claw is, and from which axis its attitude is measured)."""
    return Field(None, ge=-180, le=180, description=description)


class ClawPose(StrictModel):
    """What a key pose asks of the claw: the tip within ``tolerance`` of (x, y) when x and y are given, the claw's
    attitude within ``attitude_tolerance`` of ``attitude`` when that is given; at least one of the two."""

    x: float | None = Field(None, description="tip x, machine frame, mm")
    y: float | None = Field(None, description="tip y, machine frame, mm")
    tolerance: float = Field(1.0, gt=0, description="largest tip distance from (x, y), mm")
    attitude: float | None = attitude_field("claw attitude, from +x counter-clockwise, deg")
    attitude_tolerance: float = Field(2.0, gt=0, le=90, description="largest attitude miss, deg")

    @model_validator(mode="after")
    def _asks_something(self) -> "ClawPose":
        if (self.x is None) != (self.y is None):
            raise ValueError("give both x and y of the tip's target (mm), or neither")
        if self.x is None and self.attitude is None:
            raise ValueError("a key pose asks the tip's position (x, y, mm), the claw's attitude (deg), or both: "
                             "give one")
        return self

    @property
    def tip(self) -> tuple[float, float] | None:
        """(x, y) of the tip's target, mm; None when the pose asks only an attitude."""
        return None if self.x is None or self.y is None else (self.x, self.y)


def pose_names(cls, poses: dict) -> dict:
    """A field validator for a ``[key_poses]`` table's names: letters, digits and _ (rule names are built from them),
    none ending in _attitude (its rule would read as another pose's attitude rule).  Use:
    ``_pose_names = field_validator("key_poses")(pose_names)``."""
    for name in poses:
        if not name.replace("_", "").isalnum():
            raise ValueError(f"key pose name {name!r}: letters, digits and _ only")
        if name.endswith("_attitude"):
            raise ValueError(f"key pose name {name!r} may not end in _attitude")
    return poses
