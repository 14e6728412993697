"""The JSON Schemas of skinhil's files (:mod:`skinhil.schemas`): valid draft 2020-12, every
field described, the ranges the loaders enforce, every example campaign and scenario file
valid, a renamed or missing key refused in one line naming its place, and the field
reference page rendered from them current.

The outputs of real runs are validated where those runs already happen: the score file,
truth lines and process lines in tests/test_dut_scoring.py and tests/test_task_scoring.py,
a bench folder (summary, score files, process lines) in tests/test_bench_campaign.py.
"""

from __future__ import annotations

import copy
import json
import tomllib
from pathlib import Path
from typing import Any

import pytest
from harness.serve import REPO
from jsonschema import Draft202012Validator

from skinhil.campaign import campaign_file
from skinhil.campaign.campaign_file import load_campaign
from skinhil.campaign.rig import RIG_KEYS
from skinhil.campaign.summary_file import new_summary
from skinhil.cli.serve import write_score
from skinhil.errors import ConfigError
from skinhil.schemas import names, schema, validate
from skinhil.schemas.render import PAGE, render
from skinhil.scoring import DecisionScoreboard
from skinhil.scoring.score_file import score_record
from skinhil.world import scenario_file

EXAMPLES = REPO / "examples"
SMOKE = EXAMPLES / "campaigns" / "smoke.toml"
EXPECTED = {"campaign", "campaign-summary", "listen-summary-line", "ready-line", "scenario",
            "score", "serve-summary-line", "truth-line"}


def _resolve(node: dict[str, Any], root: dict[str, Any]) -> tuple[dict[str, Any],
                                                                  dict[str, Any]]:
    ref = node.get("$ref", "")
    if not ref:
        return node, root
    doc, _, pointer = ref.partition("#")
    target = schema(doc.rsplit(":", 1)[1]) if doc else root
    base = target
    for part in pointer.strip("/").split("/") if pointer.strip("/") else []:
        target = target[part]
    return _resolve({**target, **{k: v for k, v in node.items() if k != "$ref"}}, base)


def _fields(node: dict[str, Any], root: dict[str, Any], path: str = "$"
            ) -> list[tuple[str, dict[str, Any]]]:
    """Every (path, schema) of a named field under ``node``."""
    node, root = _resolve(node, root)
    out = []
    for key, sub in {**node.get("properties", {}), **node.get("patternProperties", {})}.items():
        resolved, sub_root = _resolve(sub, root)
        out.append((f"{path}.{key}", resolved))
        out += _fields(sub, root, f"{path}.{key}")
    for sub in node.get("oneOf", []):
        out += _fields(sub, root, path)
    if isinstance(node.get("items"), dict):
        out += _fields(node["items"], root, f"{path}[]")
    return out


def test_every_format_has_a_schema_and_each_is_valid() -> None:
    assert EXPECTED <= set(names())
    for name in names():
        Draft202012Validator.check_schema(schema(name))
    for name in EXPECTED:
        assert schema(name)["$id"] == f"urn:skinhil:schema:{name}"


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_every_field_is_described(name: str) -> None:
    """The schemas are the field reference: no field without a description."""
    root = schema(name)
    fields = _fields(root, root)
    assert len(fields) >= 4, name
    bare = [path for path, node in fields if not node.get("description")
            and not path.endswith("[]")]
    assert not bare, f"{name}: fields without a description: {bare}"


def test_the_reference_page_is_rendered_from_the_schemas() -> None:
    """docs/reference/files.md is what ``python -m skinhil.schemas.render`` writes."""
    assert PAGE.read_text(encoding="utf-8") == render(), \
        "run: python -m skinhil.schemas.render"
    text = render()
    for name in EXPECTED:
        assert f"Schema `{name}`" in text


@pytest.mark.parametrize("path", sorted((EXAMPLES / "scenarios").glob("*.toml"))
                         + sorted((EXAMPLES / "campaigns").glob("*.toml")),
                         ids=lambda p: p.name)
def test_every_example_file_is_valid(path: Path) -> None:
    validate("campaign" if path.parent.name == "campaigns" else "scenario",
             tomllib.loads(path.read_text(encoding="utf-8")), str(path))


def test_the_scenario_schema_has_the_loaders_ranges() -> None:
    s = schema("scenario")["properties"]
    contact = s["contact"]["items"]["properties"]
    indenter = s["indenter"]["items"]["properties"]
    for props, limits in ((contact, scenario_file.CONTACT_LIMITS),
                          (indenter, scenario_file.INDENTER_LIMITS)):
        for key, (lo, hi) in limits.items():
            assert (props[key]["minimum"], props[key]["maximum"]) == (lo, hi), key
    assert set(contact) == set(scenario_file.COMMON_KEYS).union(
        *scenario_file.MOTION_KEYS.values())
    assert set(indenter) == set(scenario_file.INDENTER_KEYS)
    assert s["contact"]["maxItems"] == scenario_file.MAX_CONTACTS
    assert s["indenter"]["maxItems"] == scenario_file.MAX_INDENTERS


def test_the_campaign_schema_has_the_loaders_keys() -> None:
    s = schema("campaign")
    assert set(s["properties"]) == set(campaign_file.TOP_KEYS)
    assert set(s["properties"]["parameters"]["properties"]) == set(campaign_file.PARAMETERS)
    assert set(s["properties"]["scenario"]["items"]["properties"]) == set(
        campaign_file.SCENARIO_KEYS)
    assert set(s["$defs"]["rig"]["properties"]) == set(RIG_KEYS)
    assert s["properties"]["scenario"]["maxItems"] == campaign_file.MAX_SCENARIOS
    assert s["properties"]["repetitions"]["maximum"] == campaign_file.MAX_REPETITIONS


def _score(tmp_path: Path) -> dict[str, Any]:
    """A score file written by serve's writer, every DECISION outcome in its log."""
    board = DecisionScoreboard(0.3, is_known=lambda sid: sid < 100)
    board.onset(0, 0)
    board.decision(0, 1000, confidence=0.5, token=7)
    board.decision(1, 2000)
    board.onset(1, 10_000)
    board.decision(999, 11_000)
    board.decision(2, 12_000, running=False)
    board.advance(10_000_000)
    board.decision(1, 10_000_001)
    write_score(tmp_path / "score.json", score_record(board))
    out: dict[str, Any] = json.loads((tmp_path / "score.json").read_text())
    return out


def test_a_score_file_is_valid_and_a_renamed_or_missing_key_is_one_line(
        tmp_path: Path) -> None:
    score = _score(tmp_path)
    validate("score", score)
    cases = {
        "renamed": (lambda d: d.__setitem__("onset", d.pop("onsets")), "$",
                    "lacks a key and has unknown key(s) 'onset'"),
        "missing": (lambda d: d.pop("tasks"), "$", "tasks"),
        "outcome": (lambda d: d["log"][0].__setitem__("outcome", "lucky"), "$.log[0].outcome",
                    "one of"),
        "negative": (lambda d: d.__setitem__("misses", -1), "$.misses", "[0, inf]"),
        "huge value": (lambda d: d.__setitem__("accuracy", "x" * 10**6), "$.accuracy",
                       "type"),
    }
    for label, (change, where, word) in cases.items():
        bad = copy.deepcopy(score)
        change(bad)
        with pytest.raises(ConfigError) as caught:
            validate("score", bad, "score.json")
        text = str(caught.value)
        assert "\n" not in text and len(text) < 400, (label, text)
        assert f"score.json: {where}" in text and word in text, (label, text)


def test_a_summary_is_valid_and_its_outcomes_closed() -> None:
    summary = new_summary(load_campaign(SMOKE), "a pty")
    validate("campaign-summary", summary)
    summary["cases"].append({"id": "x", "scenario": "random", "parameters": {"seed": 1},
                             "repetition": 1, "seed": 1, "outcome": "skipped", "message": "",
                             "criteria": [], "errors": [], "rig": {"board": None,
                                                                   "link": None},
                             "started": "", "wall_s": 0.0, "folder": "f"})
    with pytest.raises(ConfigError, match=r"\$\.cases\[0\]\.outcome = 'skipped'"):
        validate("campaign-summary", summary)


def test_truth_lines_are_one_of_their_types() -> None:
    validate("truth-line", {"type": "marker", "t_us": 0, "stimulus_id": 3, "phase": "onset"})
    with pytest.raises(ConfigError):
        validate("truth-line", {"type": "marker", "t_us": 0, "stimulus_id": 3,
                                "phase": "middle"})
    with pytest.raises(ConfigError):
        validate("truth-line", {"type": "guess"})


def test_an_unknown_schema_is_one_line() -> None:
    with pytest.raises(ConfigError, match="no schema named 'nope'"):
        validate("nope", {})
