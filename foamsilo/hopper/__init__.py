"""Steady hopper stresses of a Mohr-Coulomb material (Gremaud & Matthews).

``radial``: Jenike's radial fields (eqs 16-17); ``dg``: the Discontinuous
Galerkin solver of the hyperbolic stress system in tau = -ln r (sec. 5);
``transition``: abrupt changes of wall angle (sec. 6).
"""
