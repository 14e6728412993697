"""The reference answerers' fitted parameters: ``skinhil/data/reference_fit.json``, written by
``python benchmarks/fit_reference_answerers.py`` on training seeds of a suite only, with its
provenance (suite, version, seeds, SNR, the command) beside the values."""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

from skinhil.errors import ConfigError

FIT_FILE = "reference_fit.json"
"""The file's name in the package's ``data`` folder."""


def reference_fit() -> dict[str, Any]:
    """The fitted parameters and their provenance (the file's JSON object)."""
    text = resources.files("skinhil").joinpath("data", FIT_FILE).read_text(encoding="utf-8")
    fit: dict[str, Any] = json.loads(text)
    for key in ("suite", "suite_version", "seeds", "force", "vibration", "slip"):
        if key not in fit:
            raise ConfigError(f"skinhil/data/{FIT_FILE} has no {key!r}: refit it with "
                              "python benchmarks/fit_reference_answerers.py")
    return fit
