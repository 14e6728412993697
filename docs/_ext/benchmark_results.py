"""Sphinx directive ``skinhil-benchmarks``: one table per ``benchmarks/results/*.json`` file
(written by the benchmark scripts through ``benchmarks/results.py``), with the machine, the
command and the date of the run. No figure on the page is typed by hand."""

from __future__ import annotations

import glob
import json
import os
from typing import Any

from doc_tables import table
from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx

RESULTS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "benchmarks", "results")


def _value(fig: dict[str, Any]) -> str:
    value = fig["value"]
    text = f"{value:,.4g}" if isinstance(value, float) else f"{value:,}" if isinstance(
        value, int) else str(value)
    return f"{text} {fig.get('unit', '')}".strip()


def load_results(directory: str = RESULTS) -> list[dict[str, Any]]:
    """Every result file, sorted by benchmark name."""
    out = []
    for path in sorted(glob.glob(os.path.join(directory, "*.json"))):
        with open(path, encoding="utf-8") as fh:
            out.append(json.load(fh))
    return out


class BenchmarkResults(Directive):
    """``.. skinhil-benchmarks::``: a section per result file."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        out: list[nodes.Node] = []
        for result in load_results():
            self.state.document.settings.record_dependencies.add(
                os.path.join(RESULTS, f"{result['benchmark']}.json"))
            section = nodes.section(ids=[nodes.make_id(f"bench-{result['benchmark']}")])
            section += nodes.title(text=result["title"])
            m = result["machine"]
            load = " ".join(f"{x:.2f}" for x in result.get("load_average", []))
            about = (f"{m['cpu']}, {m['cores']} cores, {m['os']}; Python {m['python']}, "
                     f"numpy {m['numpy']}, numba {m['numba']}; load average at the end "
                     f"{load}; {result['date']}")
            section += nodes.paragraph(text=about)
            section += nodes.literal_block(result["command"], result["command"])
            section += table(["figure", "measured", "target"],
                              [[f["name"], _value(f), f.get("target", "")]
                               for f in result["figures"]])
            out.append(section)
        if not out:
            out.append(nodes.paragraph(text="No benchmark result is recorded yet."))
        return out


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("skinhil-benchmarks", BenchmarkResults)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
