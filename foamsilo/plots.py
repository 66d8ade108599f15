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


def labelled_loglog(ax: Any, rows: list[dict[str, Any]], x: str, y: str, point: str,
                    label: str) -> None:  # fmt: skip
    """Draw a log-log work-precision line: ``rows[x]`` against 100 ``rows[y]`` (%).

    Each point is labelled with ``rows[point]`` (its resolution).
    """
    xs = [r[x] for r in rows]
    ys = [100 * r[y] for r in rows]
    ax.loglog(xs, ys, "o-", label=label)
    for xi, yi, r in zip(xs, ys, rows, strict=True):
        ax.annotate(str(r[point]), (xi, yi), fontsize=6, xytext=(3, 3), textcoords="offset points")
