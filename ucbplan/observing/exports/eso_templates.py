"""The user's ESO p2 templates (``--eso-templates FILE``): names and keywords of the acquisition
and science templates, so that OB bodies (and ``--create``) carry complete templates.

ESO's template names and keywords depend on the instrument and its instrument-package version,
so ucbplan does not guess them; the user copies them from an existing OB or the instrument's
template manual into a small YAML file (docs/exports.md)::

    acquisition:
      name: XSHOOTER_slt_acq
      parameters: {}               # ESO keyword: value, written as given
    science:
      name: XSHOOTER_slt_obs_Stare
      exptime_keyword: KEYWORD.OF.EXPTIME  # the template's exposure-time keyword [s]
      nexp_keyword: KEYWORD.OF.NEXP        # its exposure-count keyword
      parameters: {}
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ucbplan.errors import InputFileError, shorten
from ucbplan.inputs import is_number, load_yaml

_KINDS = ("acquisition", "science")
_KEYS = {
    "acquisition": {"name", "parameters"},
    "science": {"name", "parameters", "exptime_keyword", "nexp_keyword"},
}
#: Longest template name or keyword accepted [characters].
_MAX_NAME = 80


@dataclass(frozen=True, slots=True)
class EsoTemplate:
    """One p2 template: its name, fixed keyword values, and the keywords ucbplan fills in."""

    name: str
    parameters: dict[str, Any] = field(default_factory=dict)
    exptime_keyword: str | None = None
    nexp_keyword: str | None = None

    def values(self, exptime_s: float, n_exp: int) -> dict[str, Any]:
        """Keyword → value for ``setTemplateParams``: the fixed ones and the block's exposures."""
        out = dict(self.parameters)
        if self.exptime_keyword:
            out[self.exptime_keyword] = exptime_s
        if self.nexp_keyword:
            out[self.nexp_keyword] = n_exp
        return out


@dataclass(frozen=True, slots=True)
class EsoTemplates:
    """The acquisition and science templates of an ``--eso-templates`` file."""

    acquisition: EsoTemplate | None
    science: EsoTemplate | None


def _word(path: Path, where: str, value: Any) -> str:
    if not isinstance(value, str) or not value.strip() or len(value) > _MAX_NAME:
        raise InputFileError(
            f"{path}: {where}: expected a template name or ESO keyword (text, at most "
            f"{_MAX_NAME} characters), got {shorten(value, 40)}"
        )
    return value.strip()


def _parameters(path: Path, where: str, value: Any) -> dict[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InputFileError(
            f"{path}: {where}: expected a mapping ESO keyword: value, got {shorten(value, 40)}"
        )
    out: dict[str, Any] = {}
    for key, item in value.items():
        if not (isinstance(item, str | bool) or is_number(item)):
            raise InputFileError(
                f"{path}: {where}.{shorten(key, 40)}: expected text, a number or true/false, "
                f"got {shorten(item, 40)}"
            )
        out[_word(path, f"{where} key", key)] = item
    return out


def _template(path: Path, kind: str, entry: Any) -> EsoTemplate:
    if not isinstance(entry, dict):
        raise InputFileError(f"{path}: {kind}: expected a mapping with name: TEMPLATE_NAME")
    unknown = set(map(str, entry)) - _KEYS[kind]
    if unknown:
        raise InputFileError(
            f"{path}: {kind}: unknown key {shorten(sorted(unknown)[0], 40)}; expected "
            f"{', '.join(sorted(_KEYS[kind]))}"
        )
    optional = {
        k: _word(path, f"{kind}.{k}", entry[k])
        for k in ("exptime_keyword", "nexp_keyword")
        if entry.get(k) is not None
    }
    return EsoTemplate(
        _word(path, f"{kind}.name", entry.get("name")),
        _parameters(path, f"{kind}.parameters", entry.get("parameters")),
        **optional,
    )


def load_eso_templates(path: Path | str) -> EsoTemplates:
    """Read and check an ``--eso-templates`` YAML file (see the module docstring).

    Raises
    ------
    InputFileError
        One line naming the file and the field.
    """
    path = Path(path)
    doc = load_yaml(path, "ESO templates file")
    if not isinstance(doc, dict) or not doc or set(map(str, doc)) - set(_KINDS):
        raise InputFileError(
            f"{path}: expected a mapping with acquisition: and/or science: templates, got "
            f"{shorten(doc, 60)}"
        )
    acq, sci = (_template(path, k, doc[k]) if k in doc else None for k in _KINDS)
    return EsoTemplates(acq, sci)
