"""Sphinx configuration of skinhil's documentation (MyST Markdown pages, the furo theme).

Build: ``python -m sphinx -W -b html docs OUT`` (warnings are errors; ``pip install -e
".[docs]"``). The command-line reference is generated from skinhil's argparse parsers and the
benchmarks page from ``benchmarks/results/*.json`` at build time (``docs/_ext``)."""

from __future__ import annotations

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)  # this checkout's skinhil, firmware_sim and protocols
sys.path.insert(0, os.path.join(HERE, "_ext"))

project = "skinhil"
author = "skinhil contributors"
copyright = "skinhil contributors, MIT licence"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "cli_reference",
    "benchmark_results",
    "channel_map",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "figures/REPORT.md", "**/.ipynb_checkpoints"]
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3

html_theme = "furo"
html_title = "skinhil"

autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
# Optional extras (NWB, LSL, plotting) are not needed to read their docstrings.
autodoc_mock_imports = ["pynwb", "hdmf", "nwbinspector", "pylsl", "matplotlib", "dask"]
# Docstrings are written for readers of the code: their cross-references to private names
# and to types the docs do not document are not warnings.
nitpicky = False
suppress_warnings = ["autodoc.import_object"]
