"""The dataset file: HDF5 in the layout of the Spiking Heidelberg Digits (SHD), which tonic's
``tonic.datasets.hsd.HSD`` reads (docs/dataset.md: every field, its type and unit).

- ``spikes/times``: per sample, its spike times (s, float64) from the sample's start;
- ``spikes/units``: per sample, the spikes' sensor addresses (uint16, the wire's ``addr``);
- ``labels``: per sample, the index of its class in ``extra/keys`` (int16; -1: its task has
  no classes, its target is in the truth datasets below);
- ``extra/keys``: the class names (bytes, as SHD's);
- ``extra/seed`` (and ``extra/speaker``, the same data: SHD's slot for a sample's source,
  which tonic's SHD reads), ``extra/case``, ``extra/task`` (indices into
  ``extra/case_names``, ``extra/task_names``), ``extra/trial``, ``extra/start_s``,
  ``extra/duration_s``, and the truth: ``extra/x_mm``, ``extra/y_mm``, ``extra/force_n``,
  ``extra/frequency_hz``, ``extra/slip_onset_s``;
- ``extra/units/``: each sensor's place: ``x_m``, ``y_m``, ``z_m`` (its spring's midpoint
  at rest), ``layer`` (1-3 in a layer, 12 or 23 between layers) and ``spring`` (its two
  masses' 1-based numbers);
- the root's attributes: the suite and its version, the seeds, the cases, the model (skin
  size, step, SNR), the response window and what a sample is.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from skinhil.dataset.samples import Sample
from skinhil.model.geometry import Mesh, sensor_positions
from skinhil.output_files import atomic_path

FORMAT = "skinhil-dataset-shd"
"""The root's ``format`` attribute."""
FORMAT_VERSION = 1
"""The root's ``format_version``: a change of a field's meaning is a new version."""


def write_samples(path: Path, samples: Sequence[Sample], keys: Sequence[str],
                  labels: Sequence[int], mesh: Mesh, attrs: Mapping[str, Any]) -> Path:
    """Write ``samples`` with their ``labels`` (indices into ``keys``, -1: none), the
    sensors' places of ``mesh`` and the root attributes ``attrs`` to ``path`` (written
    whole or not at all); returns ``path``."""
    cases = list(dict.fromkeys(s.case for s in samples))
    tasks = list(dict.fromkeys(s.task for s in samples))
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as f:
        times = f.create_dataset("spikes/times", (len(samples),),
                                 dtype=h5py.vlen_dtype(np.float64))
        units = f.create_dataset("spikes/units", (len(samples),),
                                 dtype=h5py.vlen_dtype(np.uint16))
        for i, s in enumerate(samples):
            times[i] = (s.t_us - s.start_us) * 1e-6
            units[i] = s.units
        f["spikes/times"].attrs["unit"] = "s, from the sample's start"
        f["labels"] = np.asarray(labels, dtype=np.int16)
        extra = f.create_group("extra")
        extra["keys"] = np.array([k.encode() for k in keys], dtype=object).astype("S")
        extra["case_names"] = np.array([c.encode() for c in cases], dtype="S")
        extra["task_names"] = np.array([t.encode() for t in tasks], dtype="S")
        columns: dict[str, tuple[Any, str]] = {
            "seed": ([s.seed for s in samples], "int64"),
            "case": ([cases.index(s.case) for s in samples], "uint8"),
            "task": ([tasks.index(s.task) for s in samples], "uint8"),
            "trial": ([s.trial for s in samples], "int32"),
            "start_s": ([s.start_us * 1e-6 for s in samples], "float64"),
            "duration_s": ([(s.end_us - s.start_us) * 1e-6 for s in samples], "float64"),
            "x_mm": ([s.x_mm for s in samples], "float64"),
            "y_mm": ([s.y_mm for s in samples], "float64"),
            "force_n": ([s.force_n for s in samples], "float64"),
            "frequency_hz": ([s.frequency_hz for s in samples], "float64"),
            "slip_onset_s": ([math.nan if s.slip_us is None else (s.slip_us - s.start_us) * 1e-6
                              for s in samples], "float64"),
        }
        for name, (values, dtype) in columns.items():
            extra.create_dataset(name, data=np.asarray(values, dtype=dtype), shape=(len(samples),))
        extra["speaker"] = extra["seed"]  # a hard link: tonic's SHD reads extra/speaker
        place = sensor_positions(mesh)
        unit = extra.create_group("units")
        for axis, name in enumerate(("x_m", "y_m", "z_m")):
            unit[name] = place[:, axis]
        unit["layer"] = mesh.layer_of_spring.astype(np.int16)
        unit["spring"] = (mesh.springs + 1).astype(np.int32)
        for key, value in attrs.items():
            f.attrs[key] = value
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
    return path
