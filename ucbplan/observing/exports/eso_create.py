"""Create the OBs of an ``eso-p2`` export in an ESO p2 container with ESO's ``p2api``.

``ucbplan export BLOCKS --to eso-p2 --create --container ID`` is a dry run by default: it lists
the OBs, their bodies and time windows that would be created, without a connection. With
``--no-dry-run`` it logs in (``p2api.ApiConnection``) and, per OB, calls ``createOB``, copies the
body (target, constraint set, description) into it and ``saveOB``, then
``getAbsoluteTimeConstraints`` / ``saveAbsoluteTimeConstraints`` with the OB's window, then
``createTemplate`` / ``setTemplateParams`` for each template the body names (``--eso-templates``;
without it the templates are left to p2, :mod:`.eso_ob`). ``p2api`` is an optional dependency
(``ucbplan[eso]``), imported only here and only when a connection is made.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from ucbplan.errors import InputError, UcbplanError, shorten

#: p2api environments: ESO's demo server, Paranal and La Silla production.
P2_ENVIRONMENTS = ("demo", "production", "production_lasilla")
#: The OB fields the body sets (the rest of the OB is p2's).
_BODY_KEYS = ("target", "constraints", "obsDescription")


class P2Api(Protocol):
    """The p2api calls used (``p2api.ApiConnection`` has them)."""

    def createOB(self, containerId: int, name: str) -> tuple[dict[str, Any], str]: ...
    def saveOB(self, ob: dict[str, Any], version: str) -> tuple[dict[str, Any], str]: ...
    def getAbsoluteTimeConstraints(self, obId: int) -> tuple[Any, str]: ...
    def saveAbsoluteTimeConstraints(
        self,
        obId: int,
        timeConstraints: list[dict[str, str]],
        version: str,
    ) -> tuple[Any, str]: ...
    def createTemplate(self, obId: int, name: str) -> tuple[dict[str, Any], str]: ...
    def setTemplateParams(
        self, obId: int, template: dict[str, Any], params: dict[str, Any], version: str
    ) -> tuple[dict[str, Any], str]: ...


@dataclass
class DryRunApi:
    """Stands in for ``p2api.ApiConnection``: records each call, creates nothing.

    OB ids are negative placeholders (-1, -2, …).
    """

    calls: list[tuple[str, dict[str, Any]]] = field(default_factory=list)

    def createOB(self, containerId: int, name: str) -> tuple[dict[str, Any], str]:
        self.calls.append(("createOB", {"containerId": containerId, "name": name}))
        ob = {"obId": -sum(c[0] == "createOB" for c in self.calls), "name": name}
        return {**ob, **{k: {} for k in _BODY_KEYS}}, "dry-run"

    def saveOB(self, ob: dict[str, Any], version: str) -> tuple[dict[str, Any], str]:
        self.calls.append(("saveOB", {"ob": ob}))
        return ob, version

    def getAbsoluteTimeConstraints(self, obId: int) -> tuple[Any, str]:
        return [], "dry-run"

    def saveAbsoluteTimeConstraints(
        self,
        obId: int,
        timeConstraints: list[dict[str, str]],
        version: str,
    ) -> tuple[Any, str]:
        self.calls.append(("saveAbsoluteTimeConstraints", {"obId": obId, "tc": timeConstraints}))
        return timeConstraints, version

    def createTemplate(self, obId: int, name: str) -> tuple[dict[str, Any], str]:
        self.calls.append(("createTemplate", {"obId": obId, "name": name}))
        return {"templateId": -len(self.calls), "templateName": name, "parameters": []}, "dry-run"

    def setTemplateParams(
        self,
        obId: int,
        template: dict[str, Any],
        params: dict[str, Any],
        version: str,
    ) -> tuple[dict[str, Any], str]:
        self.calls.append(("setTemplateParams", {"obId": obId, "params": params}))
        return template, version


@dataclass(frozen=True, slots=True)
class CreatedOb:
    """One OB created (or, in a dry run, that would be)."""

    ob_id: int
    name: str
    target: str
    windows: tuple[tuple[str, str], ...]


def _obs(doc: Mapping[str, Any]) -> list[dict[str, Any]]:
    obs = doc.get("obs") if isinstance(doc, Mapping) else None
    if not isinstance(obs, list) or not all(
        isinstance(o, dict) and isinstance(o.get("ob"), dict) for o in obs
    ):
        raise InputError(
            "create: the eso-p2 export has no OB bodies; re-export with this ucbplan version"
        )
    return obs


def _add_templates(api: P2Api, ob_id: int, templates: list[dict[str, Any]]) -> None:
    """Attach each named template (acquisition first) and set its ESO keywords."""
    for template in templates:
        if not template.get("name"):
            continue
        tpl, version = api.createTemplate(ob_id, template["name"])
        params = template.get("eso_parameters") or {}
        known = {p.get("name") for p in tpl.get("parameters") or [] if isinstance(p, dict)}
        missing = sorted(set(params) - known) if known else []
        if missing:  # p2api's setTemplateParams would drop them without a word
            raise ValueError(
                f"template {template['name']} has no keyword {missing[0]}; check `eso_templates`"
            )
        if params:
            api.setTemplateParams(ob_id, tpl, params, version)


def create_obs(doc: Mapping[str, Any], api: P2Api, container_id: int) -> list[CreatedOb]:
    """Create every OB of an ``eso-p2`` export document in the p2 container ``container_id``.

    Raises
    ------
    UcbplanError
        A p2 call failed: one line with p2's message and the OBs already created.
    """
    created: list[CreatedOb] = []
    for entry in _obs(doc):
        body, windows = entry["ob"], entry["absoluteTimeConstraints"]
        try:
            ob, version = api.createOB(container_id, body["obsDescription"]["name"])
            for key in _BODY_KEYS:
                ob[key] = {**(ob.get(key) or {}), **body[key]}
            ob, version = api.saveOB(ob, version)
            _, tc_version = api.getAbsoluteTimeConstraints(ob["obId"])
            api.saveAbsoluteTimeConstraints(ob["obId"], windows, tc_version)
            _add_templates(api, ob["obId"], body.get("templates", []))
        except Exception as exc:  # p2api raises P2Error, requests its own: report all alike
            done = ", ".join(f"{c.name} ({c.ob_id})" for c in created) or "none"
            raise UcbplanError(
                f"p2: creating OB {shorten(body['obsDescription']['name'], 40)} failed: "
                f"{shorten(' '.join(map(str, getattr(exc, 'args', ()))), 160)}; OBs created "
                f"before it: {shorten(done, 120)}"
            ) from exc
        spans = tuple((w["from"], w["to"]) for w in windows)
        created.append(CreatedOb(int(ob["obId"]), ob["name"], body["target"]["name"], spans))
    return created


def creation_report(created: Sequence[CreatedOb], container_id: int, dry_run: bool) -> str:
    """Lines for the terminal: one per OB with its id, target and windows (UTC)."""
    verb = "would create" if dry_run else "created"
    lines = [f"p2 container {container_id}: {verb} {len(created)} OBs (windows UTC)"]
    for c in created:
        spans = ", ".join(f"{a}..{b}" for a, b in c.windows)
        lines.append(f"  {'(dry run)' if dry_run else c.ob_id}  {c.name}  {c.target}  {spans}")
    if dry_run:
        lines.append("dry run: nothing was sent; add --no-dry-run to create them")
    return "\n".join(lines) + "\n"


def connect(environment: str, username: str, password: str) -> P2Api:
    """Log in to p2 with ``p2api`` (imported here: an optional dependency).

    Raises
    ------
    UcbplanError
        p2api missing (how to install it), unknown environment, or the login failed.
    """
    if environment not in P2_ENVIRONMENTS:
        raise InputError(
            f"p2_environment: expected one of {', '.join(P2_ENVIRONMENTS)}, "
            f"got {shorten(environment, 40)}"
        )
    try:
        import p2api
    except ImportError:
        raise UcbplanError(
            "create needs ESO's p2api: pip install 'ucbplan[eso]' (or pip install p2api)"
        ) from None
    try:
        api: P2Api = p2api.ApiConnection(environment, username, password)
    except Exception as exc:  # P2Error, or a connection error from requests
        raise UcbplanError(
            f"p2: login to {environment} as {shorten(username, 40)} failed: "
            f"{shorten(' '.join(map(str, getattr(exc, 'args', ()))), 160)}"
        ) from exc
    return api


def create_from_export(
    content: bytes,
    container_id: int,
    *,
    dry_run: bool = True,
    connection: P2Api | None = None,
) -> str:
    """Create (or, by default, list) the OBs of an ``eso-p2`` export; the report text.

    ``connection`` is a logged-in p2api connection (:func:`connect`); it is required unless
    ``dry_run``.
    """
    doc = json.loads(content)
    if dry_run:
        api: P2Api = DryRunApi()
    elif connection is None:
        raise InputError("`dry_run=False`: no p2 connection (give `p2_user`)")
    else:
        api = connection
    return creation_report(create_obs(doc, api, container_id), container_id, dry_run)
