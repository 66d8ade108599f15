"""Analytic discharge laws and exact solutions (plain Python, vectorised).

Cross-checks for the simulations: Beverloo-type laws, the gas-assisted
model of Zhou et al. 2019, and exact solutions of the equations the solver
integrates.
"""

from foamsilo.analytic.beverloo import (
    ZHOU_PLANAR_Q,
    ZHOU_PLANAR_Q_SPREAD,
    beverloo_2d,
    beverloo_2d_constant,
)

__all__ = [
    "ZHOU_PLANAR_Q",
    "ZHOU_PLANAR_Q_SPREAD",
    "beverloo_2d",
    "beverloo_2d_constant",
]

# Submodules: beverloo, zhou (Table I, eqs 1-25), fit, exact, figures, cli
