"""Figures written off-screen (matplotlib's Agg backend), each file whole or not at all."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any


def subplots(ncols: int = 1, size: tuple[float, float] = (6, 4.2), **kw: Any) -> tuple[Any, Any]:
    """``plt.subplots`` on the Agg backend (no display needed), 120 dpi."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(1, ncols, figsize=size, dpi=120, **kw)


def finish(fig: Any, axes: Any | Iterable[Any], path: Path, legend_size: float = 8) -> Path:
    """Grid and legend on each axis, then save ``path`` through a temporary file."""
    import matplotlib.pyplot as plt

    for ax in axes if isinstance(axes, Iterable) else [axes]:
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=legend_size)
    fig.tight_layout()
    path = Path(path)
    tmp = path.with_name(path.stem + ".tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    tmp.replace(path)
    return path
