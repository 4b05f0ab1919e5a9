"""Spec files: TOML -> validated, frozen model of the file's ``kind``.

Each kind's model lives in its own module and is imported only when a spec of that kind is loaded,
so a run never imports the code of mechanisms its scene does not use.
"""

from __future__ import annotations

import difflib
import importlib
from dataclasses import dataclass
from pathlib import Path

from pydantic import BaseModel

from synthesis.errors import SpecError
from synthesis.spec.common import read_toml, validate

#: kind -> "module:ModelClass"
KINDS: dict[str, str] = {
    "planting_fourbar": "synthesis.spec.planting:PlantingFourbarSpec",
    "guide_tube": "synthesis.spec.guide_tube:GuideTubeSpec",
    "clamp_cam": "synthesis.spec.clamp_cam:ClampCamSpec",
    "crank_rocker": "synthesis.spec.crank_rocker:CrankRockerSpec",
    "picker_double_crank": "synthesis.spec.picker:PickerDoubleCrankSpec",
    "picker": "synthesis.spec.picker:PickerSpec",
    "fourbar_path": "synthesis.spec.fourbar_path:FourbarPathSpec",
}


@dataclass(frozen=True)
class LoadedSpec:
    model: BaseModel
    path: Path
    sha256: str

    @property
    def kind(self) -> str:
        return self.model.kind

    @property
    def name(self) -> str:
        return self.model.name


def model_class(kind: str) -> type[BaseModel]:
    module, cls = KINDS[kind].split(":")
    return getattr(importlib.import_module(module), cls)


def load_spec(path: str | Path) -> LoadedSpec:
    """Read and validate a spec file; raises SpecError naming the file, field and value."""
    path = Path(path)
    data, sha = read_toml(path)
    kind = data.get("kind")
    if kind is None:
        raise SpecError(f"{path}: missing required field 'kind' (one of: {', '.join(KINDS)})")
    if kind not in KINDS:
        close = difflib.get_close_matches(str(kind), list(KINDS), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else f" (known kinds: {', '.join(KINDS)})"
        raise SpecError(f"{path}: kind: unknown kind {kind!r}{hint}")
    try:
        model = validate(model_class(kind), data, prefix=kind)
    except SpecError as exc:
        raise SpecError(f"{path}: {exc}") from None
    return LoadedSpec(model, path, sha)
