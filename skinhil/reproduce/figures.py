"""The PNG figures of ``skinhil reproduce`` (matplotlib, an optional extra, imported lazily).

One file per figure group; every panel shows each mechanics with each readout side by side
where they apply. File names are listed in :data:`FIGURES`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinhil.analysis.sweep import SweepResult
from skinhil.errors import ConfigError
from skinhil.model.psp import PSPFilterBank
from skinhil.model.stimuli import direction_conditions, figure_4a_stimulus, paper_stimuli
from skinhil.output_files import atomic_path
from skinhil.reproduce import claims
from skinhil.reproduce.compute import (
    ALL_SET,
    AMPLITUDES,
    FIGURE_SNR_DB,
    FOCUS_CONDITION,
    FOCUS_MASS,
    PAPER_SENSOR_RANK,
    TEN_SET,
    MechanicsResults,
    SupplementaryPoint,
    sensor_set_name,
)

FIGURES: dict[str, str] = {
    "fig1E_variance_explained.png": "1E: variance-explained curves per phase",
    "fig1F_information_measures.png": "1F: nPC99 and signal-information ratio per phase",
    "fig2ABC_sweeps.png": "2A-C: area, nPC ratio, SIR ratio over stiffness x damping (the "
                          "damping grid as extended for 2B/2C), with the terciles, 2A's "
                          "extremes and 2B/2C's optimum (the centroid of the top 10 %) "
                          "marked",
    "fig2T_tension.png": "2, third axis: the measures over baseline tension x stiffness and "
                         "tension x damping",
    "fig3A-E_responses.png": "3A-E: forces at M15's sensors for the 5 inputs",
    "fig3F_similarity.png": "3F: correlation index (0..1) between the inputs at M15",
    "fig4A_conditions.png": "4A: the 9 direction conditions",
    "fig4B_forces.png": "4B: spring forces of all sensors, one condition",
    "fig4C_population_raster.png": "4C: spikes of all sensors, one trial at 10 dB",
    "fig4D_sensor_raster.png": "4D: sensor #5, 50 repetitions of each condition at 10 dB",
    **{f"fig4E_psp_{m}_{r}_{a}.png": f"4E: PSP traces of sensor #5 per condition ({m}, {r} "
                                      f"readout, {a} amplitude)"
       for a in AMPLITUDES for m in ("linear", "geometric") for r in ("length", "axial")},
    "fig4F_confusion.png": "4F: confusion matrices at 10 dB for sensor #5, M15's 10 sensors "
                           "and all 338",
    "fig4G_accuracy_vs_snr.png": "4G: accuracy vs SNR for the three feature sets, with the "
                                 "range of M15's single sensors",
    "figS1_sensors_and_pca.png": "Supplementary 1: M15's sensor responses to stimulus 1 and "
                                 "the variance-explained curves per phase, per K x C (the "
                                 "paper's linear model, axial readout)",
}


def psp_figure(mechanics: str, readout: str, amplitude: str) -> str:
    """File name of Figure 4E for one mechanics, readout and amplitude."""
    return f"fig4E_psp_{mechanics}_{readout}_{amplitude}.png"


PANEL_COLUMNS = 4
"""Figures with one panel per run lay them out four a row (mechanics x readout), one row per
amplitude."""


def _panels(plt: Any, n: int, width: float, height: float) -> tuple[Any, list[Any]]:
    """A figure with ``n`` panels, :data:`PANEL_COLUMNS` a row; the unused ones hidden."""
    cols = min(n, PANEL_COLUMNS)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False,
                             layout="constrained")
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


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
    with atomic_path(path) as tmp:  # keeps the suffix: matplotlib picks the format by it
        fig.savefig(tmp, dpi=110, bbox_inches="tight")
    _pyplot().close(fig)
    return path


def fig1e(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, axes = _panels(plt, len(res), 5, 3.6)
    for ax, r in zip(axes, res, strict=True):
        n = int(np.nanmax([r.stacked.npc99_ind, r.stacked.npc99_post, 5])) + 10
        k = np.arange(1, n + 1)
        ci, cp = r.pca_ind.curve[:n], r.pca_post.curve[:n]
        ax.plot(k, ci, "o-", ms=3, label="indentation, stimulus 1")
        ax.plot(k, cp, "s-", ms=3, label="post-indentation, stimulus 1")
        ax.fill_between(k, ci, cp, alpha=0.2, color="grey",
                        label=f"area {r.measures.area:.3g}")
        ax.plot(k, r.stacked_pcas[0].curve[:n], ":", c="C0", label="indentation, 5 stacked")
        ax.plot(k, r.stacked_pcas[1].curve[:n], ":", c="C1", label="post, 5 stacked")
        ax.axhline(0.99, ls=":", c="k", lw=0.8)
        ax.set(title=f"{r.label}", xlabel="number of PCs",
               ylabel="cumulative variance explained", ylim=(0, 1.02))
        ax.legend(loc="lower right", fontsize=8)
    return _save(fig, out, "fig1E_variance_explained.png")


def fig1f(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, (a, b) = plt.subplots(2, 1, figsize=(12, 7), layout="constrained")
    x = np.arange(len(res))
    for off, attr, label in ((-0.18, "ind", "indentation"), (0.18, "post", "post-indentation")):
        a.bar(x + off, [getattr(r.measures, f"npc99_{attr}") for r in res], 0.34, label=label)
        b.bar(x + off, [getattr(r.measures, f"sir_{attr}") for r in res], 0.34, label=label)
    for ax, title in ((a, "PCs for 99% variance, stimulus 1"),
                      (b, "signal-information ratio (PC1-3), stimulus 1")):
        ax.set_xticks(x, [r.label for r in res], rotation=20, fontsize=8)
        ax.set_title(title)
        ax.legend(fontsize=8)
    return _save(fig, out, "fig1F_information_measures.png")


def _log_ticks(values: Sequence[float]) -> tuple[np.ndarray, list[str]]:
    v = np.asarray(values)
    idx = np.unique(np.linspace(0, v.size - 1, min(v.size, 5)).round().astype(int))
    return idx, [f"{v[i]:.3g}" for i in idx]


def _heatmap(ax: Any, sweep: SweepResult, name: str, title: str, plt: Any) -> None:
    values = sweep.at(name)
    img = ax.imshow(values, origin="lower", aspect="auto", cmap="viridis",
                    interpolation="nearest")
    ax.set_yticks(*_log_ticks(sweep.spec.stiffness_n_per_m))
    ax.set_xticks(*_log_ticks(sweep.spec.damping_n_s_per_m))
    ax.set(xlabel="damping C (N·s/m)", ylabel="stiffness K (N/m)", title=title)
    groups = [claims.tercile_groups(n) for n in values.shape]
    for g in groups[0][1:]:
        if g.size:
            ax.axhline(g[0] - 0.5, c="w", lw=0.8, ls="--")
    for g in groups[1][1:]:
        if g.size:
            ax.axvline(g[0] - 0.5, c="w", lw=0.8, ls="--")
    if name == "area":  # 2A: the extremes the claim excepts, hatched
        n_low_c, n_high_k = claims.extreme_counts(values.shape)
        for xy, w, h in (((-0.5, -0.5), n_low_c, values.shape[0]),
                         ((-0.5, values.shape[0] - n_high_k - 0.5), values.shape[1], n_high_k)):
            ax.add_patch(plt.Rectangle(xy, w, h, fill=False, ec="red", lw=0, hatch="///",
                                       label="2A: extremes"))
    else:  # 2B/2C: the optimum (centroid of the top region), in grid-index coordinates
        ks, cs = sweep.spec.stiffness_n_per_m, sweep.spec.damping_n_s_per_m
        loc = claims.optimum_location(values, ks, cs)
        if loc is not None:
            x = np.interp(loc[1], np.log10(cs), np.arange(len(cs)))
            y = np.interp(loc[0], np.log10(ks), np.arange(len(ks)))
            ax.plot(x, y, "wo", ms=9, mfc="none", mew=2,
                    label="optimum (centroid of the top 10 %)")
    if np.isfinite(values).any():
        i, j = np.unravel_index(int(np.nanargmax(values)), values.shape)
        ax.plot(j, i, "r*", ms=10, label="grid maximum")
    plt.colorbar(img, ax=ax)


def fig2(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, axes = plt.subplots(len(res), 3, figsize=(15, 4.2 * len(res)), squeeze=False,
                             layout="constrained")
    for row, r in zip(axes, res, strict=True):
        for ax, (name, label) in zip(row, (("area", "A: area between curves"),
                                           ("npc_ratio", "B: nPC99 ratio ind/post"),
                                           ("sir_ratio", "C: SIR ratio ind/post")), strict=True):
            _heatmap(ax, r.sweep, name, f"{label} ({r.label})", plt)
    handles: dict[str, Any] = {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncol=3,
               fontsize=8)
    return _save(fig, out, "fig2ABC_sweeps.png")


def fig2_tension(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    res = [r for r in res if r.tension_k.values]  # the amplitude the tension axis ran at
    fig, axes = plt.subplots(2 * len(res), 3, figsize=(15, 3.6 * 2 * len(res)), squeeze=False,
                             layout="constrained")
    names = (("area", "area between curves"), ("npc_ratio", "nPC99 ratio ind/post"),
             ("sir_ratio", "SIR ratio ind/post"))
    for r_i, r in enumerate(res):
        for s_i, (sweep, axis_name, values) in enumerate((
                (r.tension_k, "stiffness K (N/m)", r.tension_k.spec.stiffness_n_per_m),
                (r.tension_c, "damping C (N·s/m)", r.tension_c.spec.damping_n_s_per_m))):
            fixed = (f"C {sweep.spec.damping_n_s_per_m[0]:g} N·s/m" if s_i == 0
                     else f"K {sweep.spec.stiffness_n_per_m[0]:g} N/m")
            for ax, (name, label) in zip(axes[2 * r_i + s_i], names, strict=True):
                v = sweep.values[name].reshape(len(sweep.spec.tension_n), -1)
                img = ax.imshow(v, origin="lower", aspect="auto", cmap="viridis",
                                interpolation="nearest")
                ax.set_yticks(range(v.shape[0]), [f"{t:.3g}" for t in sweep.spec.tension_n])
                ax.set_xticks(*_log_ticks(values))
                ax.set(xlabel=axis_name, ylabel="baseline tension (N)",
                       title=f"{label} ({r.label}, {fixed})")
                plt.colorbar(img, ax=ax)
    return _save(fig, out, "fig2T_tension.png")


def _input_label(i: int, name: str) -> str:
    return f"input {i + 1} ({name})"


def fig3(plt: Any, res: Sequence[MechanicsResults], out: Path, dt_s: float) -> list[Path]:
    stimuli = paper_stimuli()
    labels = [_input_label(i, s.name) for i, s in enumerate(stimuli)]
    what = ["normal press, M15", "normal press, M16", "45° oblique press, M16",
            "shear +x, M15", "shear +y, M15"]
    fig, axes = plt.subplots(len(res), 5, figsize=(19, 3.6 * len(res)), squeeze=False,
                             sharex=True, layout="constrained")
    for row, r in zip(axes, res, strict=True):
        t = np.arange(r.responses.shape[1]) * dt_s * 1e3
        for ax, i in zip(row, range(5), strict=True):
            ax.plot(t, r.responses[i][:, r.focus_sensors] * 1e3, lw=0.8)
            ax.set(title=f"3{'ABCDE'[i]}: {labels[i]}: {what[i]}\n({r.label})",
                   xlabel="time (ms)", ylabel="M15's 10 sensors (mN)" if i == 0 else "")
            ax.title.set_fontsize(9)
    paths = [_save(fig, out, "fig3A-E_responses.png")]
    fig, axes = _panels(plt, len(res), 5.2, 4.2)
    short = [str(i + 1) for i in range(len(stimuli))]
    for ax, r in zip(axes, res, strict=True):
        img = ax.imshow(r.similarity, vmin=0, vmax=1, cmap="viridis")
        for (i, j), v in np.ndenumerate(r.similarity):
            ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=8,
                    color="k" if v > 0.6 else "w")
        ax.set_xticks(range(5), short)
        ax.set_yticks(range(5), short)
        ax.set(xlabel="input", ylabel="input",
               title=f"3F: per-sensor mean index at M15 ({r.label})")
        plt.colorbar(img, ax=ax, label="max(mean ρ, 0): 0 uncorrelated, 1 identical")
    paths.append(_save(fig, out, "fig3F_similarity.png"))
    return paths


def _condition_label(i: int) -> str:
    return f"{i}: {direction_conditions()[i].name.replace('deg_', '°, ')}"


def fig4(plt: Any, res: Sequence[MechanicsResults], out: Path, dt_s: float) -> list[Path]:
    paths = []
    conds = direction_conditions()
    fig, ax = plt.subplots(figsize=(4, 4))
    for i, s in enumerate(conds):
        f = s.peak_forces_n[FOCUS_MASS - 1]
        ax.annotate("", xy=(f[0], f[1]), xytext=(0, 0), arrowprops={"arrowstyle": "->"})
        ax.text(f[0] * 1.08, f[1] * 1.08, str(i), fontsize=8)
    f = figure_4a_stimulus().peak_forces_n[FOCUS_MASS - 1]
    ax.annotate("", xy=(f[0], f[1]), xytext=(0, 0),
                arrowprops={"arrowstyle": "->", "color": "red"})
    ax.text(f[0] * 0.55, f[1] * 0.75, "paper's 4A\n(not decoded)", fontsize=7, c="red")
    ax.set(xlim=(-0.6, 0.6), ylim=(-0.6, 0.6), aspect="equal", xlabel="Fx (N)",
           ylabel="Fy (N)", title=f"4A: force on M{FOCUS_MASS} per condition")
    paths.append(_save(fig, out, "fig4A_conditions.png"))

    fig, axes = _panels(plt, len(res), 6, 3.6)
    for ax, r in zip(axes, res, strict=True):
        f = r.condition_forces
        lim = float(np.abs(f).max() * 1e3) or 1.0
        img = ax.imshow(f.T * 1e3, aspect="auto", cmap="RdBu_r", origin="lower",
                        extent=(0, f.shape[0] * dt_s * 1e3, 0, f.shape[1]), vmin=-lim, vmax=lim)
        ax.set(xlabel="time (ms)", ylabel="sensor", title=f"4B: forces, condition "
               f"{_condition_label(FOCUS_CONDITION)} ({r.label})")
        plt.colorbar(img, ax=ax, label="mN (tension > 0)")
    paths.append(_save(fig, out, "fig4B_forces.png"))

    fig, axes = _panels(plt, len(res), 6, 3.6)
    for ax, r in zip(axes, res, strict=True):
        steps, chans = np.nonzero(r.population_raster)
        ax.plot(steps * dt_s * 1e3, chans, "|", ms=2, c="k")
        ax.set(xlabel="time (ms)", ylabel="sensor", ylim=(0, r.population_raster.shape[-1]),
               xlim=(0, r.population_raster.shape[0] * dt_s * 1e3),
               title=f"4C: one trial of condition {FOCUS_CONDITION} at {FIGURE_SNR_DB:g} dB "
               f"({r.label})")
    paths.append(_save(fig, out, "fig4C_population_raster.png"))

    paths.append(_fig4d(plt, res, out, dt_s))
    for r in res:
        paths.append(_fig4e(plt, r, out, dt_s))
    paths.append(_fig4f(plt, res, out))
    paths.append(_fig4g(plt, res, out))
    return paths


def _paper_column(r: MechanicsResults) -> int:
    return int(np.flatnonzero(r.focus_sensors == r.paper_sensor)[0])


def _fig4d(plt: Any, res: Sequence[MechanicsResults], out: Path, dt_s: float) -> Path:
    fig, axes = _panels(plt, len(res), 6.5, 7.5)
    for ax, r in zip(axes, res, strict=True):
        trials = r.sensor_trials[:, :, :, _paper_column(r)]  # (9, reps, steps)
        n_cond, reps, n_steps = trials.shape
        ms = min(6.0, 500.0 / (n_cond * reps))  # a tick about one row high (points)
        for c in range(n_cond):
            rep, steps = np.nonzero(trials[c])
            ax.plot(steps * dt_s * 1e3, c * reps + rep, "|", ms=ms, mew=1.0, c=f"C{c // 3}")
            if c:
                ax.axhline(c * reps - 0.5, c="grey", lw=0.5)
        ax.axvspan(0, r.feature_spec.window_s * 1e3, color="orange", alpha=0.12,
                   label="decoder window")
        ax.set_yticks([c * reps + reps / 2 for c in range(n_cond)],
                      [_condition_label(c) for c in range(n_cond)], fontsize=8)
        ax.set(xlabel="time (ms)", ylim=(-0.5, n_cond * reps - 0.5),
               xlim=(0, n_steps * dt_s * 1e3),
               title=f"4D: sensor {r.paper_sensor} (#{PAPER_SENSOR_RANK} of M{FOCUS_MASS}), "
               f"{reps} repetitions per condition, {FIGURE_SNR_DB:g} dB ({r.label})")
        ax.title.set_fontsize(9)
        ax.legend(loc="upper right", fontsize=7)
    return _save(fig, out, "fig4D_sensor_raster.png")


def _fig4e(plt: Any, r: MechanicsResults, out: Path, dt_s: float) -> Path:
    trials = r.sensor_trials
    psp = PSPFilterBank(trials.shape[-1], dt_s).filter(trials)[..., _paper_column(r)]
    top = float(psp.max()) * 1.05 or 1.0
    t = np.arange(psp.shape[2]) * dt_s * 1e3
    spec = r.feature_spec
    fig, axes = plt.subplots(3, 3, figsize=(12, 8), sharex=True, sharey=True,
                             layout="constrained")
    for c, ax in enumerate(axes.ravel()):
        ax.plot(t, psp[c].T, c="grey", lw=0.4, alpha=0.5)
        ax.plot(t, psp[c].mean(axis=0), c=f"C{c // 3}", lw=1.6, label="mean")
        for b in range(1, spec.n_bins + 1):
            ax.axvline(b * spec.bin_s * 1e3, c="orange", lw=0.6, ls=":")
        ax.set(title=f"condition {_condition_label(c)}", ylim=(0, top))
        ax.title.set_fontsize(9)
        if c >= 6:
            ax.set_xlabel("time (ms)")
        if c % 3 == 0:
            ax.set_ylabel("PSP (eq. 12)")
    fig.suptitle(f"4E: PSP traces of sensor {r.paper_sensor} (#{PAPER_SENSOR_RANK} of "
                 f"M{FOCUS_MASS}), {trials.shape[1]} repetitions at {FIGURE_SNR_DB:g} dB, "
                 f"mean in colour; dotted: the decoder's 10 ms bins ({r.label})",
                 fontsize=10)
    return _save(fig, out, psp_figure(r.mechanics, r.readout, r.amplitude))


def _fig4f(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, axes = plt.subplots(len(res), 3, figsize=(13, 4.2 * len(res)), squeeze=False,
                             layout="constrained")
    for row, r in zip(axes, res, strict=True):
        at = r.at_figure_snr()
        for ax, name in zip(row, (r.paper_set, TEN_SET, ALL_SET), strict=True):
            cv = at[name]
            img = ax.imshow(cv.confusion_fraction, vmin=0, vmax=1, cmap="Blues")
            ax.set_xticks(range(9))
            ax.set_yticks(range(9))
            label = r.paper_label if name == r.paper_set else name
            ax.set(xlabel="predicted condition", ylabel="true condition",
                   title=f"4F: {label}, {FIGURE_SNR_DB:g} dB\naccuracy {cv.accuracy:.2f} "
                   f"({r.label})")
            ax.title.set_fontsize(9)
        plt.colorbar(img, ax=row[-1], label="fraction of the true condition's trials")
    return _save(fig, out, "fig4F_confusion.png")


def _fig4g(plt: Any, res: Sequence[MechanicsResults], out: Path) -> Path:
    fig, axes = _panels(plt, len(res), 5.6, 4.2)
    for ax, r in zip(axes, res, strict=True):
        finite = [s for s in r.snrs_db if math.isfinite(s)]
        top = (max(finite) if finite else 0.0) + 10.0
        x = [s if math.isfinite(s) else top for s in r.snrs_db]
        singles = np.array([[cv.accuracy for cv in r.decoding[sensor_set_name(int(s))]]
                            for s in r.focus_sensors])
        ax.fill_between(x, singles.min(axis=0), singles.max(axis=0), color="grey", alpha=0.25,
                        label=f"range of M{FOCUS_MASS}'s single sensors")
        for name, label, style in (
                (r.paper_set, r.paper_label, "o-"),
                (TEN_SET, TEN_SET, "s-"), (ALL_SET, ALL_SET, "^-")):
            ax.errorbar(x, [cv.accuracy for cv in r.decoding[name]],
                        [cv.accuracy_std for cv in r.decoding[name]], fmt=style, capsize=3,
                        label=label)
        ax.set_xticks(x, [f"{s:g}" if math.isfinite(s) else "inf" for s in r.snrs_db])
        ax.axhline(1 / 9, ls=":", c="k", label="chance 1/9")
        ax.axhspan(claims.WELL_ABOVE_CHANCE / 9, claims.WELL_BELOW_FULL, color="orange",
                   alpha=0.08, label="'well above chance, well below 100 %'")
        ax.set(xlabel="SNR (dB)", ylabel="accuracy (5-fold CV, mean ± std of folds)",
               ylim=(0, 1.05), title=f"4G: decoding accuracy vs SNR ({r.label})")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=3,
               fontsize=8)
    return _save(fig, out, "fig4G_accuracy_vs_snr.png")


def figs1(plt: Any, points: Sequence[SupplementaryPoint], out: Path, dt_s: float) -> Path:
    """Supplementary Figure 1: per K x C, the sensor responses and the PCA curves."""
    n = int(round(math.sqrt(len(points))))
    fig, axes = plt.subplots(n, 2 * n, figsize=(4.2 * 2 * n, 3.0 * n), squeeze=False,
                             layout="constrained")
    for idx, p in enumerate(points):
        row, col = divmod(idx, n)
        a, b = axes[n - 1 - row][2 * col], axes[n - 1 - row][2 * col + 1]
        t = np.arange(p.forces.shape[0]) * dt_s * 1e3
        a.plot(t, p.forces * 1e3, lw=0.7)
        a.set(title=f"K {p.stiffness_n_per_m:g} N/m, C {p.damping_n_s_per_m:g} N·s/m",
              xlabel="time (ms)", ylabel="M15's sensors (mN)")
        k = np.arange(1, 21)
        b.plot(k, p.curve_ind[:20], "o-", ms=2, label="indentation")
        b.plot(k, p.curve_post[:20], "s-", ms=2, label="post")
        b.set(ylim=(0, 1.02), xlabel="PCs", title="variance explained")
        a.title.set_fontsize(8)
        b.title.set_fontsize(8)
    axes[0][1].legend(fontsize=7)
    fig.suptitle("Supplementary 1: stimulus 1 on the paper's linear model (axial readout); "
                 "rows: stiffness (low at the bottom), columns: damping (low at the left)",
                 fontsize=10)
    return _save(fig, out, "figS1_sensors_and_pca.png")


def write_figures(res: Sequence[MechanicsResults], out: Path, dt_s: float,
                  supplementary: Sequence[SupplementaryPoint] = ()) -> list[Path]:
    """Write every figure of :data:`FIGURES` into ``out`` (the 4E of each run; Supplementary 1
    if ``supplementary`` is given); returns the paths."""
    plt = _pyplot()
    try:
        paths = [fig1e(plt, res, out), fig1f(plt, res, out), fig2(plt, res, out),
                 fig2_tension(plt, res, out)]
        paths += fig3(plt, res, out, dt_s)
        paths += fig4(plt, res, out, dt_s)
        if supplementary:
            paths.append(figs1(plt, supplementary, out, dt_s))
    finally:
        plt.close("all")
    return paths
