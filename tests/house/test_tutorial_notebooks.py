"""The tutorial notebooks (docs/tutorials/*.ipynb) run in a real Jupyter kernel with no network.

Each notebook is executed by nbclient in an IPython kernel started from this interpreter, from
the repository root (the notebooks read the bundled ``catalogs/``). A cell put first blocks
every socket connection in the kernel and snapshots astropy's state
(``test_no_global_state.snapshot``); a cell put last checks that no connection was tried, and
that the state is as it was (but the warning filters, which the notebooks' own cells may set).
Any error in a cell fails the test with the cell's traceback. A fast test checks that the
notebooks read the typed results (``plan.goals``, ``plan.strategies`` …), not meta dicts.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from support.network import BLOCK_SOCKETS

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "docs" / "tutorials").glob("*.ipynb"))

#: Put first: no network in the kernel (every attempt recorded, then refused), and the state.
FIRST = (
    BLOCK_SOCKETS
    + f"""
import sys
sys.path.insert(0, {str(ROOT / "tests")!r})
from support.state import snapshot as _snapshot
_before = _snapshot()
"""
)

#: Put last: no connection tried, astropy's state as the notebook found it (all but the
#: warning filters, which a notebook's own cells may set: ``warnings.simplefilter``).
LAST = """
def _state(snap):
    return {k: v[:-1] if k == "offline scope" else v for k, v in snap.items() if "warn" not in k}

assert _attempts == [], _attempts
_after = _snapshot()
assert _state(_after) == _state(_before), {k: v for k, v in _after.items() if _before[k] != v}
"""


def test_there_are_three_notebooks_stored_without_outputs() -> None:
    assert len(NOTEBOOKS) == 3
    for path in NOTEBOOKS:
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        code = [c for c in cells if c["cell_type"] == "code"]
        assert code and all(not c.get("outputs") for c in code), path.name


def _code(path: Path) -> str:
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebooks_use_the_public_api(path: Path) -> None:
    """What a notebook user should write: the typed records, not the meta dicts a file's header
    holds; no private attribute; the plan's keywords by their names, not the old ones."""
    from ucbplan.api.plan_options import OLD_NAMES

    code = _code(path)
    assert ".meta[" not in code and ".meta.get(" not in code, path.name
    assert re.search(r"\.\_[a-z]", code) is None, path.name
    old = [name for name in OLD_NAMES if re.search(rf"\b{name}\s*=", code)]
    assert old == [], (path.name, old)


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_in_a_kernel_with_no_network(path: Path) -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    nb = nbformat.read(path, as_version=4)
    nb.cells.insert(0, nbformat.v4.new_code_cell(FIRST))
    nb.cells.append(nbformat.v4.new_code_cell(LAST))
    client = nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}}
    )
    client.execute()  # raises CellExecutionError (with the traceback) on any error
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o["output_type"] == "error"]
    assert errors == []
