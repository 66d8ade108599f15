"""The patches of a silo mesh and their OpenFOAM types, per representation."""

from __future__ import annotations

#: OpenFOAM patch type of each physical group, per representation (in patch order)
PATCH_TYPES: dict[str, dict[str, str]] = {
    "planar": {"walls": "wall", "orifice": "patch", "atmosphere": "patch", "frontAndBack": "empty"},
    "axisymmetric": {
        "walls": "wall",
        "orifice": "patch",
        "atmosphere": "patch",
        "front": "wedge",
        "back": "wedge",
    },
    "3d": {"walls": "wall", "orifice": "patch", "atmosphere": "patch"},
}


def patch_order(representation: str) -> list[str]:
    """Return the patches of a mesh, in the order gmsh numbers them (and OpenFOAM lists them)."""
    return list(PATCH_TYPES[representation])
