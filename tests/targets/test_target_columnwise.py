"""Many target files validated column by column (issue 34): the same targets, field by field and
bit for bit, and the same first error with the same message as the one-file path, on the bundled
catalogs, the bad-input corpus and random mutations (tests/targets/target_corpus.py)."""

from __future__ import annotations

import copy
import random
from pathlib import Path

import pytest
import yaml
from support.targets import BASE
from target_corpus import groups_of, outcome, snapshot, write_corpus

from ucbplan.targets import columnwise as cw
from ucbplan.targets import load_target, load_target_documents, load_target_files

ROOT = Path(__file__).resolve().parents[2]
HM_CNC = ROOT / "catalogs" / "hm-cnc-simulated.yaml"


@pytest.fixture(scope="module")
def corpus_files(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    return write_corpus(tmp_path_factory.mktemp("corpus"), 400, seed=34)


def _alone(paths: list[Path]) -> object:
    """The one-file path: each file's documents in turn, the first error raised."""
    return outcome(lambda: [t for p in paths for t in load_target_documents(p)])


def test_each_file_loads_as_alone(corpus_files: list[Path]) -> None:
    for path in corpus_files:
        assert outcome(lambda p=path: load_target_files([p])) == _alone([path]), path.name


def test_groups_raise_the_first_error_or_give_the_same_targets(corpus_files: list[Path]) -> None:
    groups = groups_of(corpus_files, seed=35)
    oks = 0
    for g in groups:
        paths = [corpus_files[k] for k in g]
        got = outcome(lambda p=paths: load_target_files(p))
        assert got == _alone(paths), [p.name for p in paths]
        oks += got[0] == "ok"
    assert oks >= len(groups) // 5  # the likely valid groups load


def test_the_columns_take_most_plain_documents(corpus_files: list[Path]) -> None:
    """Not a vacuous comparison: the columns build a good share of the corpus and refuse
    (hand to the one-file path) some plain documents."""
    built = cw._built([cw._read(p) for p in corpus_files])
    assert sum(t is not None for t in built) >= 60
    assert sum(len(t) > 1 for t in built if t is not None) >= 3  # catalogs too
    assert sum(t is None for t in built) >= 60


def test_hm_cnc_is_built_by_the_columns_as_alone() -> None:
    ((target,),) = cw._built([cw._read(HM_CNC)])
    assert snapshot(target) == snapshot(load_target(HM_CNC))
    assert target.t_ref is not load_target(HM_CNC).t_ref


def test_each_target_has_its_own_epoch(tmp_path: Path) -> None:
    paths = []
    for k in range(3):
        doc = copy.deepcopy(BASE) | {"name": f"T{k}"}
        paths.append(tmp_path / f"t{k}.yaml")
        paths[-1].write_text(yaml.safe_dump(doc), "utf-8")
    targets = load_target_files(paths)
    assert len({id(t.t_ref) for t in targets}) == 3
    targets[0].t_ref.format = "jd"
    assert targets[1].t_ref.format == "isot"


def test_a_read_error_after_a_bad_file_is_not_the_one_raised(tmp_path: Path) -> None:
    bad = copy.deepcopy(BASE)
    bad["lisa"]["f_gw"] = "6e-3 km"
    first, second = tmp_path / "a.yaml", tmp_path / "b.yaml"
    first.write_text(yaml.safe_dump(bad), "utf-8")
    second.write_text("name: [unclosed", "utf-8")
    assert outcome(lambda: load_target_files([first, second])) == _alone([first, second])
    assert outcome(lambda: load_target_files([second, first])) == _alone([second, first])
    missing = tmp_path / "missing.yaml"
    assert outcome(lambda: load_target_files([missing, first])) == _alone([missing, first])


@pytest.mark.parametrize("seed", range(3))
def test_shuffled_catalog_folders(tmp_path: Path, corpus_files: list[Path], seed: int) -> None:
    rng = random.Random(seed)
    valid = [p for p in corpus_files if p.name.startswith("v")]
    paths = rng.sample(valid, 30)
    assert outcome(lambda: load_target_files(paths)) == _alone(paths)


def test_a_path_that_is_none_fails_in_its_turn(tmp_path: Path) -> None:
    bad = copy.deepcopy(BASE)
    bad["lisa"]["f_gw"] = "6e-3 km"
    first = tmp_path / "a.yaml"
    first.write_text(yaml.safe_dump(bad), "utf-8")
    assert outcome(lambda: load_target_files([first, None])) == _alone([first])
    with pytest.raises(TypeError):
        load_target_files([None, first])
