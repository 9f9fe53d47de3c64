"""PNG plots of energy histories (matplotlib, headless)."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def energyPlot(path, t, series, title="QDEM energy"):
    """series: {label: list of values}; writes a PNG with the total in black."""
    fig, ax = plt.subplots(figsize=(8, 4.5))
    total = None
    for k, v in series.items():
        ax.plot(t, v, label=k, lw=1.2)
        total = list(v) if total is None else [a + b for a, b in zip(total, v)]
    if total is not None:
        ax.plot(t, total, "k--", lw=1.5, label="sum")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("energy [J]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

__all__ = ["energyPlot"]
