"""Config fuzz test: deterministic mutations of the main job's W1 config (PickFork-v1).

Every mutation (see ``config_mutations.py``) goes through the normal path of a gym
config, ``load_gym_config`` then ``gymnasium.make``, with the standard plugins. A
mutation either builds (only the documented valid values) or fails with a
``ConfigError`` naming the key path; any other exception, or a nonsense value
that builds, fails the test. The mutated configs record in the test process
(``params.writer_process: false``): a writer child costs seconds to start and stop
per build, and the corpus is about the config, not the recording (the unmutated main
job builds with its writer child). Every rejected mutation fails before or while
MuJoCo compiles and runs by default (about 10 s); an accepted one builds the whole W1
scene: a fixed sample of them runs by default, all of them in the ``slow`` test
(``.ci/run``), as does the ``slow`` variant that applies two rejected mutations at
once (a fixed pairing) and needs an error naming one.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Optional

import gymnasium as gym
import pytest
from config_mutations import Mutation, apply, mutations

import embodichain_tasks
from embodichain_core.config.errors import ConfigError
from embodichain_core.config.loader import load_gym_config

MAIN_JOB = Path(embodichain_tasks.__file__).parent / "configs" / "main_job.json"
CORPUS = mutations()
REJECTED = [m for m in CORPUS if m.expect == "error"]
ACCEPTED = [m for m in CORPUS if m.expect == "ok"]
#: Every fourth accepted mutation (the corpus is ordered by config path, so the sample spans it).
ACCEPTED_SAMPLE = ACCEPTED[::4]


@pytest.fixture(scope="module")
def main_job(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The main job's config, recording (if ever) into a temporary folder."""
    data = json.loads(MAIN_JOB.read_text())
    data["env"]["dataset"]["lerobot"]["params"]["save_path"] = str(tmp_path_factory.mktemp("fuzz_datasets"))
    return data


@pytest.fixture(scope="module")
def base_config(main_job: dict) -> dict:
    """What the mutations change: the main job's config, its recorder writing in this process."""
    data = copy.deepcopy(main_job)
    data["env"]["dataset"]["lerobot"]["params"]["writer_process"] = False
    return data


def build(data: dict) -> Optional[BaseException]:
    """Build the env of ``data`` like ``run-env`` does; return the exception, if any."""
    env = None
    try:
        task_id, cfg, _ = load_gym_config(data)
        cfg.verbose = False
        env = gym.make(task_id, cfg=cfg)
    except Exception as err:  # noqa: BLE001 - the test classifies every exception
        return err
    finally:
        if env is not None:
            env.close()
    return None


def outcome(mutation: Mutation, err: Optional[BaseException]) -> str:
    """``"ok"``, or why the mutation's result is wrong."""
    if mutation.expect == "ok":
        return "ok" if err is None else f"rejected a valid value: {type(err).__name__}: {err}"
    if err is None:
        return "accepted a nonsense value"
    if not isinstance(err, ConfigError):
        return f"traceback instead of a ConfigError: {type(err).__name__}: {err}"
    missing = [part for part in mutation.must_name() if part not in str(err)]
    return "ok" if not missing else f"the error does not name {missing}: {err}"


def _check_all(base: dict, corpus: list[Mutation]) -> None:
    failures = {}
    for mutation in corpus:
        result = outcome(mutation, build(apply(base, mutation)))
        if result != "ok":
            failures[mutation.id] = result
    summary = "\n".join(f"{key}: {value}" for key, value in failures.items())
    assert not failures, f"{len(failures)}/{len(corpus)} mutations handled wrongly:\n{summary}"


def test_corpus_is_large_and_deterministic() -> None:
    assert len(CORPUS) >= 150
    assert len(REJECTED) >= 150
    assert [m.id for m in CORPUS] == [m.id for m in mutations()]
    assert len({m.id for m in CORPUS}) == len(CORPUS)
    kinds = {m.label for m in CORPUS}
    assert {
        "delete",
        "str",
        "none",
        "nan",
        "inf",
        "negative",
        "zero",
        "swapped",
        "short",
        "huge",
        "typo_rset",
        "typo_intervall",
    } <= kinds


def test_unmutated_main_job_builds(main_job: dict, base_config: dict) -> None:
    assert build(main_job) is None
    assert build(base_config) is None


def test_mutations_fail_with_a_config_error_naming_the_key(base_config: dict) -> None:
    _check_all(base_config, REJECTED)


def test_a_sample_of_valid_values_builds(base_config: dict) -> None:
    assert 4 <= len(ACCEPTED_SAMPLE) < len(ACCEPTED)
    _check_all(base_config, ACCEPTED_SAMPLE)


@pytest.mark.slow
def test_every_valid_value_builds(base_config: dict) -> None:
    assert len(ACCEPTED) >= 30
    _check_all(base_config, ACCEPTED)


def _pairs() -> list[tuple[Mutation, Mutation]]:
    """Rejected mutations paired with one half the corpus away, when neither path contains the other."""
    half = len(REJECTED) // 2
    pairs = [(a, b) for a, b in zip(REJECTED[:half], REJECTED[half:])]
    return [(a, b) for a, b in pairs if not (a.path.startswith(b.path) or b.path.startswith(a.path))]


@pytest.mark.slow
def test_two_bad_values_at_once_still_give_a_config_error(base_config: dict) -> None:
    failures = {}
    for first, second in _pairs():
        try:
            data = apply(apply(base_config, first), second)
        except (KeyError, IndexError, TypeError):  # the first change removed what the second edits
            continue
        err = build(data)
        results = [outcome(first, err), outcome(second, err)]
        if "ok" not in results:
            failures[f"{first.id} + {second.id}"] = results[0]
    assert len(_pairs()) >= 100
    assert not failures, failures


def test_outcome_classifies_results() -> None:
    bad = Mutation("rigid_object[0].attrs.mass", "negative", -1.0, "error")
    assert outcome(bad, None) == "accepted a nonsense value"
    assert outcome(bad, KeyError("mass")).startswith("traceback")
    assert outcome(bad, ConfigError("rigid_object[0].attrs", "bad")).startswith("the error does not name")
    assert outcome(bad, ConfigError("rigid_object[0].attrs.mass", "must be >= 0")) == "ok"
    good = Mutation("light.direct[0].intensity", "zero", 0.0, "ok")
    assert outcome(good, None) == "ok"
    assert outcome(good, ConfigError("x", "y")).startswith("rejected")
    assert math.isnan(apply({"a": {"b": [1, 2]}}, Mutation("a.b[1]", "nan", math.nan, "error"))["a"]["b"][1])
