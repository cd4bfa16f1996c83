"""A local fake of ESO's p2 server (127.0.0.1, no network) for the eso-p2 --create tests."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest

TOKEN = "fake-token"


#: Keywords the fake p2's templates have (a real template lists its own).
TEMPLATE_KEYWORDS = ("DET.WIN1.UIT1", "SEQ.NEXPO", "TEL.AG.GUIDESTAR")


p2api_module = pytest.importorskip("p2api.p2api")


class P2State:
    """State of the fake p2: OBs, their versions and every request received."""

    def __init__(self) -> None:
        self.requests: list[dict[str, Any]] = []
        self.obs: dict[int, dict[str, Any]] = {}
        self.windows: dict[int, list[dict[str, str]]] = {}
        self.fail_on_ob: int | None = None
        self.templates: dict[int, tuple[int, dict[str, Any]]] = {}


def _handler(state: P2State) -> type[BaseHTTPRequestHandler]:
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


TEMPLATES_YAML = """\
acquisition:
  name: XSHOOTER_slt_acq
  parameters: {TEL.AG.GUIDESTAR: CATALOGUE}
science:
  name: XSHOOTER_slt_obs_Stare
  exptime_keyword: DET.WIN1.UIT1
  nexp_keyword: SEQ.NEXPO
"""


@pytest.fixture
def fake_p2(monkeypatch: pytest.MonkeyPatch) -> Iterator[P2State]:
    state = P2State()
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
