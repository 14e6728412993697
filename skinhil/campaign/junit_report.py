"""The campaign as JUnit XML, through junitparser: one ``<testsuite>`` per campaign, one
``<testcase>`` per case × repetition (classname ``campaign.scenario``). A criterion that
does not hold is a ``<failure>`` (the decoder's); a fault of the rig is an ``<error>``
(never a failure); the message says which criteria or faults, the body every figure."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from junitparser import Error, Failure, JUnitXml, TestCase, TestSuite

from skinhil.output_files import atomic_path


def write_junit(path: Path, summary: dict[str, Any]) -> None:
    """Write the cases of ``summary`` (:mod:`skinhil.campaign.summary_file`) to ``path``
    as JUnit XML, whole or not at all."""
    name = summary["campaign"]["name"]
    suite = TestSuite(name)
    for record in summary["cases"]:
        case = TestCase(record["id"], f"{name}.{record['scenario']}", record["wall_s"])
        body = json.dumps({"criteria": record["criteria"], "rig": record["rig"]}, indent=1)
        result: Failure | Error | None = None
        if record["outcome"] == "failed":
            result = Failure(record["message"], "criteria")
        elif record["outcome"] == "error":
            result = Error(record["message"], "rig")
        if result is not None:
            result.text = body
            case.result = [result]
        else:
            case.system_out = body
        suite.add_testcase(case)
    suite.update_statistics()
    xml = JUnitXml()
    xml.add_testsuite(suite)
    with atomic_path(path) as tmp:
        xml.write(str(tmp), pretty=True)
