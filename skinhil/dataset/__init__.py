"""Training data for decoders (docs/dataset.md): a suite's cases simulated offline on
training seeds, one sample per trial, written in the layout of the Spiking Heidelberg Digits
(tonic reads it).

A dataset is a room of its own above the suites, the scoring and the model: it turns a seed
into the case's trials (:mod:`skinhil.suites`), plays them offline as the board would
(:mod:`skinhil.dataset.samples`) and writes the file (:mod:`skinhil.dataset.shd_file`).
"""

from skinhil.dataset.build import Written, class_keys, dataset_cases, make_dataset
from skinhil.dataset.samples import Run, Sample, case_samples, simulate
from skinhil.dataset.seeds import check_training, parse_seeds

__all__ = ["Run", "Sample", "Written", "case_samples", "check_training", "class_keys",
           "dataset_cases", "make_dataset", "parse_seeds", "simulate"]
