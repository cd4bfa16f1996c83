"""``--create``: the eso-p2 OBs sent through ESO's own p2api to a local fake p2 server.

The fake server (``http.server`` on 127.0.0.1, no network) stands where p2api's ``demo``
environment points; p2api itself logs in, encodes every request (JSON body, bearer token, ETag
``If-Match``) and decodes the replies, so the test checks what p2 would receive.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
from test_cli_fuzz import run_cli
from test_exports_fixture import fixture_table

from ucbplan.errors import UcbplanError
from ucbplan.observing.exports import ExportOptions, export_blocks
from ucbplan.observing.exports.eso_create import (
    DryRunApi,
    connect,
    create_from_export,
    create_obs,
)

p2api = pytest.importorskip("p2api")
p2api_module = pytest.importorskip("p2api.p2api")

TOKEN = "fake-token"
#: Keywords the fake p2's templates have (a real template lists its own).
TEMPLATE_KEYWORDS = ("DET.WIN1.UIT1", "SEQ.NEXPO", "TEL.AG.GUIDESTAR")
TEMPLATES_YAML = """\
acquisition:
  name: XSHOOTER_slt_acq
  parameters: {TEL.AG.GUIDESTAR: CATALOGUE}
science:
  name: XSHOOTER_slt_obs_Stare
  exptime_keyword: DET.WIN1.UIT1
  nexp_keyword: SEQ.NEXPO
"""


class _P2:
    """State of the fake p2: OBs, their versions and every request received."""

    def __init__(self) -> None:
        self.requests: list[dict[str, Any]] = []
        self.obs: dict[int, dict[str, Any]] = {}
        self.windows: dict[int, list[dict[str, str]]] = {}
        self.fail_on_ob: int | None = None
        self.templates: dict[int, tuple[int, dict[str, Any]]] = {}


def _handler(state: _P2) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:  # quiet
            pass

        def _reply(self, code: int, body: Any, etag: str | None = None) -> None:
            data = json.dumps(body).encode()
            self.send_response(code)
            self.send_header("Content-Type", "application/json")
            if etag:
                self.send_header("ETag", etag)
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def _record(self) -> Any:
            size = int(self.headers.get("Content-Length") or 0)
            raw = self.rfile.read(size).decode() if size else ""
            is_json = self.headers.get("Content-Type") == "application/json"
            body = json.loads(raw) if is_json and raw else raw
            state.requests.append(
                {
                    "method": self.command,
                    "path": self.path,
                    "headers": dict(self.headers),
                    "body": body,
                }
            )
            return body

        def _authorised(self) -> bool:
            if self.headers.get("Authorization") != f"Bearer {TOKEN}":
                self._reply(401, {"error": "not logged in"})
                return False
            return True

        def do_POST(self) -> None:
            body = self._record()
            if self.path == "/copdemo/api/login":
                ok = "username=52052" in body and "password=secret" in body
                self._reply(200 if ok else 401, {"access_token": TOKEN} if ok else {"error": "x"})
                return
            if not self._authorised():
                return
            if self.path.endswith("/templates"):
                ob_id = int(self.path.split("/")[-2])
                tpl_id = 5000 + len(state.templates)
                tpl = {
                    "templateId": tpl_id,
                    "templateName": body["templateName"],
                    "parameters": [
                        {"name": k, "type": "number", "value": 0} for k in TEMPLATE_KEYWORDS
                    ],
                }
                state.templates[tpl_id] = (ob_id, tpl)
                self._reply(201, tpl, etag=f'"tpl{tpl_id}v1"')
                return
            container = int(self.path.split("/")[-2])
            ob_id = 1000 + len(state.obs)
            if state.fail_on_ob == len(state.obs):
                self._reply(400, {"error": ["container is not in a state to add OBs"]})
                return
            ob = {
                "obId": ob_id,
                "itemType": body["itemType"],
                "name": body["name"],
                "containerId": container,
                "target": {"name": "", "ra": "00:00:00.000"},
                "constraints": {"name": "No name", "airmass": 5.0},
                "obsDescription": {"name": body["name"]},
            }
            state.obs[ob_id] = ob
            self._reply(201, ob, etag=f'"ob{ob_id}v1"')

        def do_GET(self) -> None:
            self._record()
            if not self._authorised():
                return
            ob_id = int(self.path.split("/")[-3])
            self._reply(200, state.windows.get(ob_id, []), etag=f'"tc{ob_id}v1"')

        def do_PUT(self) -> None:
            body = self._record()
            if not self._authorised():
                return
            parts = self.path.split("/")
            if parts[-2] == "templates":
                tpl_id = int(parts[-1])
                if self.headers.get("If-Match") != f'"tpl{tpl_id}v1"':
                    self._reply(412, {"error": "stale version"})
                    return
                state.templates[tpl_id] = (int(parts[-3]), body)
                self._reply(200, body, etag=f'"tpl{tpl_id}v2"')
                return
            if parts[-1] == "absolute":
                ob_id = int(parts[-3])
                if self.headers.get("If-Match") != f'"tc{ob_id}v1"':
                    self._reply(412, {"error": "stale version"})
                    return
                state.windows[ob_id] = body
                self._reply(200, body, etag=f'"tc{ob_id}v2"')
                return
            ob_id = int(parts[-1])
            if self.headers.get("If-Match") != f'"ob{ob_id}v1"':
                self._reply(412, {"error": "stale version"})
                return
            state.obs[ob_id] = body
            self._reply(200, body, etag=f'"ob{ob_id}v2"')

    return Handler


@pytest.fixture
def fake_p2(monkeypatch: pytest.MonkeyPatch) -> Iterator[_P2]:
    state = _P2()
    server = ThreadingHTTPServer(("127.0.0.1", 0), _handler(state))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    base = f"http://127.0.0.1:{server.server_address[1]}/copdemo"
    monkeypatch.setitem(p2api_module.API_URL, "demo", f"{base}/api/v1")
    monkeypatch.setitem(p2api_module.LOGIN_URL, "demo", f"{base}/api/login")
    try:
        yield state
    finally:
        server.shutdown()
        server.server_close()


def _export() -> tuple[bytes, dict[str, Any]]:
    content = export_blocks(fixture_table(), "eso-p2", ExportOptions(acquisition_s=600.0)).content
    return content, json.loads(content)


def test_p2api_creates_each_ob_with_its_body_and_window(fake_p2: _P2) -> None:
    content, doc = _export()
    api = connect("demo", "52052", "secret")
    report = create_from_export(content, 42, dry_run=False, connection=api)
    assert len(fake_p2.obs) == len(doc["obs"]) == len(fake_p2.windows)
    for (ob_id, ob), entry in zip(sorted(fake_p2.obs.items()), doc["obs"], strict=True):
        body = entry["ob"]
        assert ob["name"] == entry["name"] and ob["containerId"] == 42
        assert ob["target"] == {**ob["target"], **body["target"]}  # p2's other fields kept
        assert ob["constraints"]["airmass"] == body["constraints"]["airmass"] == 2.0
        assert ob["constraints"]["moonDistance"] == 30 and ob["constraints"]["seeing"] == 1.0
        assert fake_p2.windows[ob_id] == entry["absoluteTimeConstraints"]
        assert f"{ob_id}  {entry['name']}" in report
    # p2api's encoding: bearer token, JSON bodies, the version of the object it modifies.
    puts = [r for r in fake_p2.requests if r["method"] == "PUT"]
    assert all(r["headers"]["Content-Type"] == "application/json" for r in puts)
    assert all(r["headers"]["If-Match"].endswith('v1"') for r in puts)
    posts = [r for r in fake_p2.requests if r["path"].endswith("/items")]
    assert [r["body"] for r in posts] == [{"itemType": "OB", "name": o["name"]} for o in doc["obs"]]


def test_dry_run_sends_nothing_and_lists_what_it_would_create(fake_p2: _P2) -> None:
    content, doc = _export()
    report = create_from_export(content, 42)
    assert not fake_p2.requests
    assert report.startswith(f"p2 container 42: would create {len(doc['obs'])} OBs")
    for entry in doc["obs"]:
        window = entry["absoluteTimeConstraints"][0]
        assert f"{entry['name']}" in report and f"{window['from']}..{window['to']}" in report
    # The dry run makes the same calls, in the same order, as the real run.
    api = DryRunApi()
    create_obs(doc, api, 42)
    assert [c[0] for c in api.calls] == ["createOB", "saveOB", "saveAbsoluteTimeConstraints"] * len(
        doc["obs"]
    )


def test_a_p2_error_is_one_line_naming_what_was_created(fake_p2: _P2) -> None:
    content, _ = _export()
    fake_p2.fail_on_ob = 1
    api = connect("demo", "52052", "secret")
    with pytest.raises(UcbplanError) as info:
        create_from_export(content, 42, dry_run=False, connection=api)
    text = str(info.value)
    assert "\n" not in text and len(text) < 400
    assert "not in a state to add OBs" in text and "HM_Cnc-001 (1000)" in text


def test_bad_login_is_one_line(fake_p2: _P2) -> None:
    with pytest.raises(UcbplanError, match="login to demo as '52052' failed"):
        connect("demo", "52052", "wrong")


def test_cli_create_is_a_dry_run_by_default(tmp_path: Path, fake_p2: _P2) -> None:
    blocks = tmp_path / "blocks.ecsv"
    fixture_table().write(blocks, format="ascii.ecsv")
    args = ["export", str(blocks), "--to", "eso-p2", "--acquisition", "600", "--create"]
    code, err = run_cli([*args, "--container", "42"])
    assert code == 0, err
    assert not fake_p2.requests
    code, err = run_cli(args)
    assert code == 2 and "--container" in err
    code, err = run_cli([*args, "--container", "42", "--no-dry-run"])
    assert code == 2 and "--p2-user" in err


def test_cli_creates_with_no_dry_run(
    tmp_path: Path, fake_p2: _P2, monkeypatch: pytest.MonkeyPatch
) -> None:
    blocks = tmp_path / "blocks.ecsv"
    fixture_table().write(blocks, format="ascii.ecsv")
    monkeypatch.setenv("UCBPLAN_P2_PASSWORD", "secret")
    args = ["export", str(blocks), "--to", "eso-p2", "--create", "--container", "7"]
    code, err = run_cli([*args, "--no-dry-run", "--p2-user", "52052"])
    assert code == 0, err
    assert len(fake_p2.obs) == 4 and all(o["containerId"] == 7 for o in fake_p2.obs.values())


def test_p2api_is_not_imported_by_the_exports() -> None:
    import subprocess
    import sys

    code = (
        "import sys, ucbplan.observing.exports, ucbplan.observing.exports.eso_create, "
        "ucbplan.cli.app; print('p2api' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def _export_with_templates(tmp_path: Path, text: str = TEMPLATES_YAML) -> bytes:
    path = tmp_path / "templates.yaml"
    path.write_text(text, encoding="utf-8")
    opts = ExportOptions(acquisition_s=600.0, eso_templates=str(path))
    return export_blocks(fixture_table(), "eso-p2", opts).content


def test_templates_from_the_file_are_attached_with_the_block_exposures(
    tmp_path: Path, fake_p2: _P2
) -> None:
    content = _export_with_templates(tmp_path)
    doc = json.loads(content)
    api = connect("demo", "52052", "secret")
    create_from_export(content, 42, dry_run=False, connection=api)
    by_ob: dict[int, list[dict[str, Any]]] = {}
    for ob_id, tpl in fake_p2.templates.values():
        by_ob.setdefault(ob_id, []).append(tpl)
    for (ob_id, _), entry in zip(sorted(fake_p2.obs.items()), doc["obs"], strict=True):
        acq, sci = by_ob[ob_id]  # acquisition first
        assert acq["templateName"] == "XSHOOTER_slt_acq"
        assert {p["name"]: p["value"] for p in acq["parameters"]}["TEL.AG.GUIDESTAR"] == (
            "CATALOGUE"
        )
        values = {p["name"]: p["value"] for p in sci["parameters"]}
        assert (
            values["DET.WIN1.UIT1"] == entry["exptime_s"] and values["SEQ.NEXPO"] == entry["n_exp"]
        )


def test_a_keyword_the_template_lacks_is_an_error_not_dropped(tmp_path: Path, fake_p2: _P2) -> None:
    content = _export_with_templates(tmp_path, TEMPLATES_YAML.replace("SEQ.NEXPO", "SEQ.NOPE"))
    api = connect("demo", "52052", "secret")
    with pytest.raises(UcbplanError, match=r"has no keyword SEQ\.NOPE"):
        create_from_export(content, 42, dry_run=False, connection=api)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("science: {name: 3}\n", "science.name: expected a template name"),
        ("science: {name: X, colour: red}\n", "science: unknown key 'colour'"),
        ("acquisition: {name: X, parameters: {A: [1]}}\n", "acquisition.parameters.'A'"),
        ("- a\n", "expected a mapping with acquisition"),
    ],
)
def test_bad_templates_file_is_one_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(UcbplanError) as info:
        _export_with_templates(tmp_path, text)
    assert message in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("extra", [["--create", "--container", "1"], ["--instrument", "uves"]])
def test_eso_options_are_refused_with_other_formats(tmp_path: Path, extra: list[str]) -> None:
    blocks = tmp_path / "blocks.ecsv"
    fixture_table().write(blocks, format="ascii.ecsv")
    code, err = run_cli(["export", str(blocks), "--to", "ics", *extra])
    assert code == 2 and f"{extra[0]} is an ESO p2 option" in err
