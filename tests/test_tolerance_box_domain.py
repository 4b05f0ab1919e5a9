"""The tolerance box stays where the spec takes its variables: every design variable a spec refuses at 0 and at -1
as "expected > 0" (a length, a radius, a speed) or "0 < ... < 90" (an acute angle) is one the analysis refuses a box
crossing (`refuse_crossing_zero`); a variable marked so that the spec takes at 0 would be refused for nothing.  The
combing chain's speed, the cam's radii and the guide way's arm were taken to -0.5 m/s, -1.5 mm: those samples were
evaluated and counted in the pass rates."""

from __future__ import annotations

import copy

import pytest

from conftest import LIBRARY
from synthesis import kinds
from synthesis.spec import load_spec
from synthesis.spec.common import read_toml, validate
from synthesis.spec.design_info import acute_variables, describe, positive_variables
from synthesis.spec.solved import set_at_path


def _refusal(model, data: dict, path: str, value: float, prefix: str) -> str | None:
    changed = copy.deepcopy(data)
    set_at_path(changed, path, value)
    try:
        validate(model, changed, prefix=prefix)
    except Exception as exc:        # noqa: BLE001 - the spec's refusal, whatever its type, is what is read
        return str(exc)
    return None


@pytest.mark.parametrize("kind", sorted(k.name for k in kinds.all_kinds() if k.example))
def test_every_variable_the_spec_holds_positive_or_acute_is_one_the_box_may_not_cross(kind):
    loaded = load_spec(LIBRARY / kinds.get(kind).example)
    info = describe(loaded.model)
    if not info:
        pytest.skip(f"{kind} declares no design variables")
    data, _ = read_toml(loaded.path)
    positive, acute = positive_variables(loaded.model), acute_variables(loaded.model)
    for name, entry in info.items():
        at_zero, below = (_refusal(type(loaded.model), data, entry["path"], v, kind) for v in (0.0, -1.0))
        said = f"{at_zero} / {below}"
        if at_zero and below and "expected > 0" in said:
            assert name in positive, (name, said)
        elif at_zero and below and "expected 0 <" in said:
            assert name in acute, (name, said)
        else:
            assert name not in positive | acute or (at_zero and below), (name, said)


def test_the_robust_refusal_reads_each_half_width_as_the_box_does(tmp_path):
    """The robust solve's up-front refusal and the box it guards (`box_of`) read a variable's half-width by one
    rule (`half_width`: its own entry first, else by unit) and test its range by one (`box_fits`)."""
    from synthesis.errors import SpecError
    from synthesis.tolerance.design import box_fits, half_width, refuse_box_outside_bounds
    text = (LIBRARY / "steering" / "steering_redesign_27.toml").read_text()
    spec = tmp_path / "st.toml"
    spec.write_text(text + "\n[tolerance]\nangle = 50.0\nsamples = 50\n[tolerance.variables]\nbase_angle = 1.0\n")
    refuse_box_outside_bounds(load_spec(spec).model, "mm", spec)          # nothing to refuse
    spec.write_text(text + "\n[tolerance]\nangle = 50.0\nsamples = 50\n")
    with pytest.raises(SpecError, match=r"\+-50 deg on base_angle: no design in its bounds \[55, 89\] deg"):
        refuse_box_outside_bounds(load_spec(spec).model, "mm", spec)
    assert half_width(("a", "b"), "deg", 1.0, 2.0, {"b": 0.0}) == 0.0
    assert half_width(("a",), "deg", 1.0, 2.0, {}) == 2.0 and half_width(("a",), "m/s", 1.0, 2.0, {}) == 0.0
    # one design (lo = hi) and an interval: strict at both ends of (0, 90)
    assert box_fits(10.0, 10.0, 9.9, acute=True) and not box_fits(10.0, 10.0, 10.0, acute=True)
    assert not box_fits(80.0, 80.0, 10.0, acute=True) and box_fits(5.0, 80.0, 10.0, acute=True)
    assert box_fits(0.0, 1.0, 0.5, acute=False) and not box_fits(0.0, 0.5, 0.5, acute=False)
