"""The paper's analyses: information content (PCA), similarity across stimuli, sweeps,
decoding versus SNR. Each module documents its choices (samples, features, windows)."""

from skinhil.analysis.correlation import sensors_of_mass, similarity_matrix, zero_lag_ncc
from skinhil.analysis.information import InformationMeasures, information_measures
from skinhil.analysis.pca import area_between, n_components_for, phase_pca, variance_explained
from skinhil.analysis.phases import PhaseWindows
from skinhil.analysis.sweep import SweepResult, SweepSpec, run_sweep

__all__ = [
    "InformationMeasures",
    "PhaseWindows",
    "SweepResult",
    "SweepSpec",
    "area_between",
    "information_measures",
    "n_components_for",
    "phase_pca",
    "run_sweep",
    "sensors_of_mass",
    "similarity_matrix",
    "variance_explained",
    "zero_lag_ncc",
]
