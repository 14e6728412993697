"""The PNG figures of ``skinhil reproduce`` (matplotlib, an optional extra, imported lazily).

One file per figure group; every panel shows the linear and the geometric mechanics side by
side where both apply. File names are listed in :data:`FIGURES`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.analysis.sweep import SweepResult
from skinhil.errors import ConfigError
from skinhil.psp import PSPFilterBank
from skinhil.reproduce.compute import FIGURE_SNR_DB, FOCUS_CONDITION, MechanicsResults
from skinhil.stimuli import direction_conditions, paper_stimuli

FIGURES: dict[str, str] = {
    "fig1E_variance_explained.png": "1E: variance-explained curves per phase",
    "fig1F_information_measures.png": "1F: nPC99 and signal-information ratio per phase",
    "fig2ABC_sweeps.png": "2A-C: area, nPC ratio, SIR ratio over stiffness x damping",
    "fig3A-E_responses.png": "3A-E: forces at M15's sensors for the 5 paper stimuli",
    "fig3F_similarity.png": "3F: cross-correlation similarity across stimuli at M15",
    "fig4A_conditions.png": "4A: the 9 direction conditions",
    "fig4B_forces.png": "4B: spring forces of all sensors, one condition",
    "fig4C_population_raster.png": "4C: spikes of all sensors, one trial",
    "fig4D_sensor_raster.png": "4D: one sensor over repeated trials",
    "fig4E_psp.png": "4E: PSP-filtered activity of that sensor and the feature bins",
    "fig4F_confusion.png": "4F: confusion matrix of the decoder",
    "fig4G_accuracy_vs_snr.png": "4G: decoding accuracy versus SNR",
}


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise ConfigError("figures need matplotlib: pip install 'skinhil[plot]'") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig: Any, out: Path, name: str) -> Path:
    path = out / name
    fig.savefig(path, dpi=110, bbox_inches="tight")
    fig.clf()
    return path


def fig1e(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, axes = plt.subplots(1, len(res), figsize=(5 * len(res), 3.6), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        n = int(np.nanmax([r.measures.npc99_ind, r.measures.npc99_post, 5])) + 10
        k = np.arange(1, n + 1)
        ci, cp = r.pca_ind.curve[:n], r.pca_post.curve[:n]
        ax.plot(k, ci, "o-", ms=3, label="indentation")
        ax.plot(k, cp, "s-", ms=3, label="post-indentation")
        ax.fill_between(k, ci, cp, alpha=0.2, color="grey",
                        label=f"area {r.measures.area:.3g}")
        ax.axhline(0.99, ls=":", c="k", lw=0.8)
        ax.set(title=f"{r.mechanics} mechanics", xlabel="number of PCs",
               ylabel="cumulative variance explained", ylim=(0, 1.02))
        ax.legend(loc="lower right", fontsize=8)
    return _save(fig, out, "fig1E_variance_explained.png")


def fig1f(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.4))
    x = np.arange(len(res))
    for off, attr, label in ((-0.18, "ind", "indentation"), (0.18, "post", "post-indentation")):
        a.bar(x + off, [getattr(r.measures, f"npc99_{attr}") for r in res], 0.34, label=label)
        b.bar(x + off, [getattr(r.measures, f"sir_{attr}") for r in res], 0.34, label=label)
    for ax, title in ((a, "PCs for 99% variance"), (b, "signal-information ratio (PC1-3)")):
        ax.set_xticks(x, [r.mechanics for r in res])
        ax.set_title(title)
        ax.legend(fontsize=8)
    return _save(fig, out, "fig1F_information_measures.png")


def _heatmap(ax: Any, sweep: SweepResult, name: str, title: str, plt: Any) -> None:
    k = np.asarray(sweep.spec.stiffness_n_per_m)
    c = np.asarray(sweep.spec.damping_n_s_per_m)
    img = ax.imshow(sweep.at(name), origin="lower", aspect="auto", cmap="viridis",
                    interpolation="nearest")
    kt = np.unique(np.linspace(0, k.size - 1, min(k.size, 5)).round().astype(int))
    ct = np.unique(np.linspace(0, c.size - 1, min(c.size, 5)).round().astype(int))
    ax.set_yticks(kt, [f"{k[i]:.3g}" for i in kt])
    ax.set_xticks(ct, [f"{c[i]:.3g}" for i in ct])
    ax.set(xlabel="damping C (N·s/m, log grid)", ylabel="stiffness K (N/m, log grid)",
           title=title)
    plt.colorbar(img, ax=ax)


def fig2(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, axes = plt.subplots(len(res), 3, figsize=(15, 4.2 * len(res)), squeeze=False,
                             layout="constrained")
    for row, r in zip(axes, res, strict=True):
        for ax, (name, label) in zip(row, (("area", "A: area between curves"),
                                           ("npc_ratio", "B: nPC99 ratio ind/post"),
                                           ("sir_ratio", "C: SIR ratio ind/post")), strict=True):
            _heatmap(ax, r.sweep, name, f"{label} ({r.mechanics})", plt)
    return _save(fig, out, "fig2ABC_sweeps.png")


def fig3(plt: Any, res: Sequence[MechanicsResults], out: Path, dt_s: float) -> list[Path]:
    names = [s.name for s in paper_stimuli()]
    fig, axes = plt.subplots(len(res), 5, figsize=(19, 3.6 * len(res)), squeeze=False,
                             sharex=True, layout="constrained")
    for row, r in zip(axes, res, strict=True):
        t = np.arange(r.responses.shape[1]) * dt_s * 1e3
        for ax, i in zip(row, range(5), strict=True):
            ax.plot(t, r.responses[i][:, r.focus_sensors] * 1e3, lw=0.8)
            ax.set(title=f"3{'ABCDE'[i]}: stimulus {names[i]} ({r.mechanics})",
                   xlabel="time (ms)", ylabel="M15's sensors (mN)" if i == 0 else "")
    paths = [_save(fig, out, "fig3A-E_responses.png")]
    fig, axes = plt.subplots(1, len(res), figsize=(4.6 * len(res), 3.8), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        img = ax.imshow(r.similarity, vmin=-1, vmax=1, cmap="RdBu_r")
        for (i, j), v in np.ndenumerate(r.similarity):
            ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=7)
        ax.set_xticks(range(5), names)
        ax.set_yticks(range(5), names)
        ax.set_title(f"3F: similarity at M15 ({r.mechanics})")
        plt.colorbar(img, ax=ax)
    paths.append(_save(fig, out, "fig3F_similarity.png"))
    return paths


def fig4(plt: Any, res: Sequence[MechanicsResults], out: Path, dt_s: float) -> list[Path]:
    paths = []
    conds = direction_conditions()
    fig, ax = plt.subplots(figsize=(4, 4))
    for i, s in enumerate(conds):
        f = s.peak_forces_n[14]
        ax.annotate("", xy=(f[0], f[1]), xytext=(0, 0), arrowprops={"arrowstyle": "->"})
        ax.text(f[0] * 1.08, f[1] * 1.08, str(i), fontsize=8)
    ax.set(xlim=(-0.6, 0.6), ylim=(-0.6, 0.6), aspect="equal", xlabel="Fx (N)",
           ylabel="Fy (N)", title="4A: force on M15 per condition")
    paths.append(_save(fig, out, "fig4A_conditions.png"))

    fig, axes = plt.subplots(1, len(res), figsize=(6 * len(res), 3.6), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        f = r.direction_forces[FOCUS_CONDITION]
        img = ax.imshow(f.T * 1e3, aspect="auto", cmap="RdBu_r", origin="lower",
                        extent=(0, f.shape[0] * dt_s * 1e3, 0, f.shape[1]),
                        vmin=-np.abs(f).max() * 1e3, vmax=np.abs(f).max() * 1e3)
        ax.set(xlabel="time (ms)", ylabel="sensor", title=f"4B: forces, condition "
               f"{FOCUS_CONDITION} ({r.mechanics})")
        plt.colorbar(img, ax=ax, label="mN")
    paths.append(_save(fig, out, "fig4B_forces.png"))

    fig, axes = plt.subplots(1, len(res), figsize=(6 * len(res), 3.6), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        steps, chans = np.nonzero(r.rasters[0])
        ax.plot(steps * dt_s * 1e3, chans, "|", ms=2, c="k")
        ax.set(xlabel="time (ms)", ylabel="sensor", ylim=(0, r.rasters.shape[-1]),
               title=f"4C: one trial at {FIGURE_SNR_DB:g} dB ({r.mechanics})")
    paths.append(_save(fig, out, "fig4C_population_raster.png"))

    fig, axes = plt.subplots(1, len(res), figsize=(6 * len(res), 3.6), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        trial, steps = np.nonzero(r.rasters[:, :, r.raster_sensor])
        ax.plot(steps * dt_s * 1e3, trial, "|", ms=3, c="k")
        ax.set(xlabel="time (ms)", ylabel="repetition", title=f"4D: sensor {r.raster_sensor}, "
               f"{r.rasters.shape[0]} repetitions ({r.mechanics})")
    paths.append(_save(fig, out, "fig4D_sensor_raster.png"))

    fig, axes = plt.subplots(1, len(res), figsize=(6 * len(res), 3.6), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        psp = PSPFilterBank(r.rasters.shape[-1], dt_s).filter(
            r.rasters[:, :, r.raster_sensor:r.raster_sensor + 1])[:, :, 0]
        t = np.arange(psp.shape[1]) * dt_s * 1e3
        mean, std = psp.mean(axis=0), psp.std(axis=0)
        ax.plot(t, mean, c="C0", label="mean over repetitions")
        ax.fill_between(t, mean - std, mean + std, alpha=0.3, color="C0", label="± std")
        ax.set(xlabel="time (ms)", ylabel="PSP (eq. 12 units)",
               title=f"4E: PSP of sensor {r.raster_sensor} ({r.mechanics})")
        ax.legend(fontsize=8)
    paths.append(_save(fig, out, "fig4E_psp.png"))

    fig, axes = plt.subplots(1, len(res), figsize=(5 * len(res), 4.2), squeeze=False)
    for ax, r in zip(axes[0], res, strict=True):
        cv = r.decoding[r.confusion_index]
        img = ax.imshow(cv.confusion_fraction, vmin=0, vmax=1, cmap="Blues")
        ax.set(xlabel="predicted condition", ylabel="true condition",
               title=f"4F: {r.snrs_db[r.confusion_index]:g} dB, acc {cv.accuracy:.2f} "
               f"({r.mechanics})")
        plt.colorbar(img, ax=ax)
    paths.append(_save(fig, out, "fig4F_confusion.png"))

    fig, ax = plt.subplots(figsize=(5, 3.6))
    for r in res:
        finite = [s for s in r.snrs_db if math.isfinite(s)]
        top = (max(finite) if finite else 0.0) + 10.0
        x = [s if math.isfinite(s) else top for s in r.snrs_db]
        ax.errorbar(x, [c.accuracy for c in r.decoding], [c.accuracy_std for c in r.decoding],
                    marker="o", capsize=3, label=r.mechanics)
        ax.set_xticks(x, [f"{s:g}" if math.isfinite(s) else "inf" for s in r.snrs_db])
    ax.axhline(1 / 9, ls=":", c="k", label="chance 1/9")
    ax.set(xlabel="SNR (dB)", ylabel="accuracy (5-fold CV)", ylim=(0, 1.05),
           title="4G: decoding accuracy vs SNR")
    ax.legend(fontsize=8)
    paths.append(_save(fig, out, "fig4G_accuracy_vs_snr.png"))
    return paths


def write_figures(res: Sequence[MechanicsResults], out: Path, dt_s: float) -> list[Path]:
    """Write every figure of :data:`FIGURES` into ``out``; returns the paths."""
    plt = _pyplot()
    try:
        paths = [fig1e(plt, res, out), fig1f(plt, res, out), fig2(plt, res, out)]
        paths += fig3(plt, res, out, dt_s)
        paths += fig4(plt, res, out, dt_s)
    finally:
        plt.close("all")
    return paths
