"""The documentation site builds with warnings as errors (``python -m sphinx -W -b html docs
OUT``), in four parts, with the command-line reference generated from the parsers (every
subcommand), the API from the docstrings, the channel map from the model and the benchmarks
page from ``benchmarks/results/*.json``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from skinhil.cli.parser import SUBCOMMANDS
from skinhil.model.geometry import spring_count
from tests.harness.serve import REPO, serve_env

pytest.importorskip("sphinx")
pytest.importorskip("myst_parser")
pytest.importorskip("furo")

PARTS = ("tutorials", "howto", "reference", "explanation")


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("site")
    res = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html",
                          str(REPO / "docs"), str(out)],
                         capture_output=True, text=True, env=serve_env(), timeout=600)
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-4000:]
    return out


def _pages(site: Path) -> list[Path]:
    return [p for p in site.rglob("*.html")
            if not {"_modules", "_static", "_sources"} & set(p.relative_to(site).parts)
            and p.name not in ("genindex.html", "search.html", "py-modindex.html")]


def test_site_has_four_parts_and_at_least_15_pages(site: Path) -> None:
    pages = _pages(site)
    assert len(pages) >= 15, sorted(str(p.relative_to(site)) for p in pages)
    for part in PARTS:
        assert list((site / part).glob("*.html")), f"no page in {part}/"
    index = (site / "index.html").read_text(encoding="utf-8")
    for caption in ("Tutorials", "How-to guides", "Reference", "Explanation"):
        assert caption in index


def test_cli_reference_lists_every_subcommand_and_its_options(site: Path) -> None:
    html = (site / "reference" / "cli.html").read_text(encoding="utf-8")
    for name in SUBCOMMANDS:
        assert f'id="cli-skinhil-{name}"' in html, f"skinhil {name} missing from the CLI page"
    for option in ("--score", "--grasp", "--suite", "--resume", "--lsl", "--view"):
        assert f"{option}" in html, option


def test_api_reference_is_generated_from_the_docstrings(site: Path) -> None:
    html = (site / "reference" / "python-api.html").read_text(encoding="utf-8")
    for name in ("skinhil.SkinModel", "protocols.SerialDecoder", "skinhil.receiver.Receiver",
                 "skinhil.transports.open_link"):
        assert f'id="{name}"' in html, name


def test_channel_map_has_one_row_per_sensor(site: Path) -> None:
    html = (site / "reference" / "channel-map.html").read_text(encoding="utf-8")
    body = html.split("<tbody>", 1)[1].split("</tbody>", 1)[0]
    assert body.count("<tr") == spring_count((6, 6))


def test_benchmarks_page_renders_every_result_file(site: Path) -> None:
    html = (site / "benchmarks.html").read_text(encoding="utf-8")
    results = sorted((REPO / "benchmarks" / "results").glob("*.json"))
    assert results, "no benchmark result to render"
    for path in results:
        result = json.loads(path.read_text(encoding="utf-8"))
        assert f'id="bench-{result["benchmark"]}"' in html, path.name
        for fig in result["figures"]:
            assert fig["name"] in html, fig["name"]
