"""The figures of docs/contact.md: each example scenario's spikes beside its ground truth.

For every ``examples/scenarios/*.toml`` it runs ``skinhil simulate --schedule FILE`` (the
default 6x6 skin and mechanics, noise-free unless ``--snr-db``) into a temporary .npz and
draws, from that file alone, the spike raster (channels ordered by the x of their spring's
middle) above the contact truth: normal and tangential force, the centroid's and the
indenter's x, the slip state. Writes ``docs/figures/contact_<name>.png`` and prints each
scenario's spikes and max strain.

Usage::

    python benchmarks/contact_figures.py [--snr-db inf] [--out docs/figures] [--smoke]

``--smoke``: the first scenario only, drawn into a temporary directory (checks that the
script runs).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from skinhil.cli import main as skinhil  # noqa: E402
from skinhil.model.skin import SkinModel, SkinParams  # noqa: E402
from skinhil.world import SLIP_STATES  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def figure(npz: Path, name: str, out: Path) -> tuple[int, float]:
    """Draw one scenario's figure from its simulate output; its spikes and max strain."""
    data = np.load(npz)
    meta = json.loads(str(data["meta"]))
    model = SkinModel(SkinParams(size=tuple(meta["size"])))  # type: ignore[arg-type]
    middle_x = 0.5 * (model.positions[model.springs[:, 0], 0]
                      + model.positions[model.springs[:, 1], 0]) * 1e3
    rank = np.empty(model.n_springs, dtype=int)
    rank[np.argsort(middle_x, kind="stable")] = np.arange(model.n_springs)
    ev, truth = data["events"], data["truth"]
    n_contacts = max(1, len(meta["contacts"]))
    rows = truth.reshape(-1, n_contacts)
    t = rows["t_us"][:, 0] * 1e-6
    fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True,
                             gridspec_kw={"height_ratios": [3, 1.4, 1.4, 0.8]})
    axes[0].plot(ev["t"] * 1e-6, rank[ev["addr"]], "|", ms=3, color="k")
    axes[0].set_ylabel("channel\n(by spring x)")
    axes[0].set_title(f"{name}: {len(ev)} spikes, max strain {100 * meta['max_strain']:.0f} %, "
                      f"{meta['mechanics']} mechanics, SNR {meta['snr_db']} dB")
    for c in range(n_contacts):
        r = rows[:, c]
        label = meta["contacts"][c] if meta["contacts"] else ""
        axes[1].plot(t, r["normal_n"], label=f"normal {label}")
        axes[1].plot(t, r["tangential_n"], "--", label=f"tangential {label}")
        axes[2].plot(t, r["indenter_x_mm"], ":", label=f"indenter x {label}")
        axes[2].plot(t, r["x_mm"], label=f"centroid x {label}")
        axes[3].step(t, r["slip"], where="post", label=label)
    axes[1].set_ylabel("force (N)")
    axes[1].legend(fontsize=7, loc="upper right")
    axes[2].set_ylabel("x (mm)")
    axes[2].legend(fontsize=7, loc="upper right")
    axes[3].set_yticks(range(len(SLIP_STATES)), SLIP_STATES, fontsize=7)
    axes[3].set_ylabel("slip")
    axes[3].set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return len(ev), float(meta["max_strain"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr-db", default="inf")
    ap.add_argument("--out", type=Path, default=REPO / "docs" / "figures")
    ap.add_argument("--smoke", action="store_true",
                    help="the first scenario only, its figure in a temporary directory: the "
                         "script runs")
    args = ap.parse_args()
    scenarios = sorted((REPO / "examples" / "scenarios").glob("*.toml"))
    with tempfile.TemporaryDirectory() as tmp:
        if args.smoke:
            scenarios, args.out = scenarios[:1], Path(tmp)
        for path in scenarios:
            npz = Path(tmp) / f"{path.stem}.npz"
            code = skinhil(["simulate", "--schedule", str(path), "--out", str(npz),
                            "--no-progress", "--snr-db", args.snr_db])
            if code:
                raise SystemExit(code)
            spikes, strain = figure(npz, path.stem, args.out / f"contact_{path.stem}.png")
            print(f"{path.stem}: {spikes} spikes, max strain {100 * strain:.1f} % -> "
                  f"{args.out / f'contact_{path.stem}.png'}", flush=True)


if __name__ == "__main__":
    main()
