"""Spec files: TOML -> validated, frozen model of the file's ``kind``.

Each kind's model lives in its own module and is imported only when a spec of that kind is loaded,
so a run never imports the code of mechanisms its scene does not use.
"""

from __future__ import annotations

import copy
import difflib
from dataclasses import dataclass, field
from pathlib import Path

from pydantic import BaseModel

from synthesis import kinds
from synthesis.errors import SpecError
from synthesis.spec.common import read_toml, shown, validate

class _Kinds:
    """The kind names of the registry (:mod:`synthesis.kinds`), read when used (so runtime kinds count)."""

    def __contains__(self, name) -> bool:
        try:
            kinds.get(name)         # the kind's own folder first: no other kind's package is imported
        except SpecError:
            return False
        return True

    def __iter__(self):
        return iter(kinds.names())


KINDS = _Kinds()


@dataclass(frozen=True)
class LoadedSpec:
    model: BaseModel
    path: Path
    sha256: str
    #: the file's data as it was read (what solved.toml rewrites; re-reading the file later could find it edited)
    data: dict | None = field(default=None, compare=False, repr=False)

    def file_data(self) -> dict:
        """A copy of the spec file's data as the run read it; a spec built without it (in Python) is read again,
        and refused if its file no longer holds the bytes whose sha256 the run records."""
        if self.data is not None:
            return copy.deepcopy(self.data)
        data, sha = read_toml(self.path)
        if sha != self.sha256:
            raise SpecError(f"{self.path}: the file changed since it was read (sha256 {self.sha256[:12]}... then, "
                            f"{sha[:12]}... now)")
        return data

    @property
    def kind(self) -> str:
        return self.model.kind

    @property
    def name(self) -> str:
        return self.model.name


def model_class(kind: str) -> type[BaseModel]:
    return kinds.get(kind).spec_model()


def load_spec(path: str | Path) -> LoadedSpec:
    """Read and validate a spec file; raises SpecError naming the file, field and value."""
    path = Path(path)
    data, sha = read_toml(path)
    as_read = copy.deepcopy(data)          # the file as read, whatever validation does with `data`
    kind = data.get("kind")
    if kind is None:
        raise SpecError(f"{path}: missing required field 'kind' (one of: {', '.join(KINDS)})")
    if not isinstance(kind, str):
        raise SpecError(f"{path}: kind: expected a string (one of: {', '.join(KINDS)}), got {type(kind).__name__}")
    name = data.get("name")
    if name is not None and not isinstance(name, str):
        raise SpecError(f"{path}: name: expected a string (the result folder's name), got {type(name).__name__}")
    if kind not in KINDS:
        close = difflib.get_close_matches(kind[:100], list(KINDS), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else f" (known kinds: {', '.join(KINDS)})"
        raise SpecError(f"{path}: kind: unknown kind {shown(kind)}{hint}")
    try:
        model = validate(model_class(kind), data, prefix=kind)
    except SpecError as exc:
        raise SpecError(f"{path}: {exc}") from None
    return LoadedSpec(model, path, sha, as_read)
