"""Matplotlib figures (Agg backend, PNG files); no computation here."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def optimum_figure(opt, path: str | Path) -> Path:
    """Plot the scanned objective of an :class:`dem.pointmass.sweep.Optimum` and mark the best."""
    x = opt.curve[opt.over]
    y = opt.curve[opt.objective]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.plot(x, y, color="C0")
    best = opt.velocity_norm if opt.objective == "velocity_norm" else opt.velocity
    ax.plot([opt.value], [best], "o", color="C3", label=f"optimum {opt.value:.3g}")
    ax.axvspan(*opt.plateau, color="C0", alpha=0.12, label="within 90%")
    ax.set_xlabel("vibration angle phi (deg)" if opt.over == "angle" else "throw number Gamma")
    ax.set_ylabel("v / (A omega cos phi)" if opt.objective == "velocity_norm" else "v (m/s)")
    held = ", ".join(f"{k}={v:g}" for k, v in opt.held.items())
    ax.set_title(f"holding {opt.hold}: {held}", fontsize=8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path
