"""``--create``: the eso-p2 OBs sent through ESO's own p2api to a local fake p2 server.

The fake server (``http.server`` on 127.0.0.1, no network) stands where p2api's ``demo``
environment points; p2api itself logs in, encodes every request (JSON body, bearer token, ETag
``If-Match``) and decodes the replies, so the test checks what p2 would receive.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from support.cli import run_cli
from support.eso_p2 import TEMPLATES_YAML, P2State
from support.exports import fixture_table

from ucbplan.errors import UcbplanError
from ucbplan.observing.exports import ExportOptions, export_blocks
from ucbplan.observing.exports.eso_create import (
    DryRunApi,
    connect,
    create_from_export,
    create_obs,
)

p2api = pytest.importorskip("p2api")


def _export() -> tuple[bytes, dict[str, Any]]:
    content = export_blocks(fixture_table(), "eso-p2", ExportOptions(acquisition_s=600.0)).content
    return content, json.loads(content)


def test_p2api_creates_each_ob_with_its_body_and_window(fake_p2: P2State) -> None:
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


def test_dry_run_sends_nothing_and_lists_what_it_would_create(fake_p2: P2State) -> None:
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


def test_a_p2_error_is_one_line_naming_what_was_created(fake_p2: P2State) -> None:
    content, _ = _export()
    fake_p2.fail_on_ob = 1
    api = connect("demo", "52052", "secret")
    with pytest.raises(UcbplanError) as info:
        create_from_export(content, 42, dry_run=False, connection=api)
    text = str(info.value)
    assert "\n" not in text and len(text) < 400
    assert "not in a state to add OBs" in text and "HM_Cnc-001 (1000)" in text


def test_bad_login_is_one_line(fake_p2: P2State) -> None:
    with pytest.raises(UcbplanError, match="login to demo as '52052' failed"):
        connect("demo", "52052", "wrong")


def test_cli_create_is_a_dry_run_by_default(tmp_path: Path, fake_p2: P2State) -> None:
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
    tmp_path: Path, fake_p2: P2State, monkeypatch: pytest.MonkeyPatch
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
    tmp_path: Path, fake_p2: P2State
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


def test_a_keyword_the_template_lacks_is_an_error_not_dropped(
    tmp_path: Path, fake_p2: P2State
) -> None:
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
