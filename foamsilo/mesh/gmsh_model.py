"""gmsh sessions: one model at a time, in a child process, patches named as built.

gmsh keeps one global model and runs long C++ calls during which Python
cannot act on Ctrl-C. :func:`build_isolated` therefore runs a builder in a
forked child process that dies at once on SIGINT (and when its parent dies),
while the parent waits, ready to stop; the builder's result or its
:class:`~foamsilo.errors.MeshError` comes back through a pipe.

Inside a builder, :class:`Session` opens the model, records the surfaces of
each patch (:meth:`Session.add_patch`) as the geometry is made, and writes
the ``.msh`` (format 2.2, ASCII: what ``gmshToFoam`` reads) with one physical
group per patch; when gmsh fails, the geometry is written beside the mesh
(``.geo_unrolled`` and ``.brep``) for inspection.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import signal
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import gmsh

from foamsilo.errors import MeshError

T = TypeVar("T")

#: Linux prctl option: a signal to get when the parent dies
_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):  # not Linux: the child may outlive a killed parent
        pass


def _child(conn: Any, builder: Callable[..., Any], args: tuple[Any, ...]) -> None:
    # Ctrl-C must end the meshing now, even inside gmsh's C++ code
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    _die_with_parent()
    try:
        conn.send(("ok", builder(*args)))
    except MeshError as exc:
        conn.send(("mesh-error", (str(exc), exc.geometry_file)))
    except BaseException as exc:  # noqa: BLE001 -- reported to the parent, whatever it is
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def build_isolated(builder: Callable[..., T], *args: Any) -> T:
    """Run ``builder(*args)`` in a forked child process and return its result.

    Raises
    ------
    MeshError
        The builder raised it, or the child died without an answer.
    KeyboardInterrupt
        Ctrl-C: the child is already gone (it dies on SIGINT); the caller
        cleans up.
    """
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, builder, args), daemon=True)
    proc.start()
    child.close()
    try:
        while not parent.poll(0.1):  # short waits: a Ctrl-C is acted on at once
            if not proc.is_alive() and not parent.poll(0):
                raise MeshError(f"the meshing process died (exit status {proc.exitcode})")
        kind, payload = parent.recv()
    except BaseException:
        if proc.is_alive():
            proc.kill()
        raise
    finally:
        proc.join(timeout=30)
        parent.close()
    if kind == "ok":
        return payload
    if kind == "mesh-error":
        message, geometry = payload
        raise MeshError(message.split(" (geometry written to")[0], geometry)
    raise MeshError(f"meshing failed: {payload}")


class Session:
    """An open gmsh model, with the patches of its boundary recorded as they are built.

    Parameters
    ----------
    name
        Model name.
    msh_file
        Where :meth:`write` puts the mesh (and a failure, the geometry).
    """

    def __init__(self, name: str, msh_file: Path) -> None:
        self.name = name
        self.msh_file = Path(msh_file)
        self.patches: dict[str, list[int]] = {}

    def __enter__(self) -> Session:
        gmsh.initialize(interruptible=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(self.name)
        return self

    def __exit__(self, *exc: object) -> None:
        gmsh.finalize()

    @property
    def occ(self) -> Any:
        """Gmsh's OpenCASCADE kernel (``gmsh.model.occ``)."""
        return gmsh.model.occ

    def fail(self, message: str) -> MeshError:
        """Return a :class:`MeshError` with the geometry written beside the mesh."""
        return MeshError(message, self.dump(self.msh_file))

    def dump(self, path: Path) -> Path:
        """Write the geometry (``.geo_unrolled``, ``.brep``) next to ``path``."""
        for suffix in (".geo_unrolled", ".brep"):
            try:
                gmsh.write(str(Path(path).with_suffix(suffix)))
            except Exception:  # noqa: BLE001 -- best effort on an already failing path
                pass
        return Path(path).with_suffix(".geo_unrolled")

    def add_patch(self, name: str, surfaces: list[int]) -> None:
        """Record boundary surfaces that belong to patch ``name``."""
        self.patches.setdefault(name, []).extend(surfaces)

    def transfinite(self, curve: int, n: int, ratio: float = 1.0) -> None:
        """N cells on a curve, growing by ``ratio`` from its first to its last point."""
        if abs(ratio - 1.0) < 1e-12:
            gmsh.model.mesh.setTransfiniteCurve(curve, n + 1)
        else:
            gmsh.model.mesh.setTransfiniteCurve(curve, n + 1, "Progression", ratio)

    def boundary(self, dim: int, tag: int) -> list[int]:
        """Tags of the entities bounding (dim, tag), in gmsh's order."""
        return [t for _, t in gmsh.model.getBoundary([(dim, tag)], oriented=False)]

    def point(self, tag: int) -> tuple[float, float, float]:
        """Coordinates of a geometry point."""
        x, y, z = gmsh.model.getValue(0, tag, [])
        return float(x), float(y), float(z)

    def curve_ends(self, curve: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """Coordinates at the start and end of a curve's parametrisation."""
        lo, hi = gmsh.model.getParametrizationBounds(1, curve)
        a = tuple(float(v) for v in gmsh.model.getValue(1, curve, [lo[0]]))
        b = tuple(float(v) for v in gmsh.model.getValue(1, curve, [hi[0]]))
        return a, b

    def write(
        self,
        patch_order: list[str],
        dump_geometry: Path | None = None,
        node_map: Callable[[float, float, float], tuple[float, float, float]] | None = None,
    ) -> None:
        """Add one physical group per patch (in ``patch_order``) and the volume; mesh; write.

        ``node_map`` moves every node of the generated mesh before it is
        written (a hopper meshed as a cylinder, then mapped onto its cone).

        Raises
        ------
        MeshError
            A patch has no surface, or gmsh failed to mesh (geometry dumped).
        """
        for name in patch_order:
            tags = sorted(set(self.patches.get(name, [])))
            if not tags:
                raise self.fail(f"no surface for patch {name!r}")
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        unknown = set(self.patches) - set(patch_order)
        if unknown:
            raise self.fail(f"surfaces recorded for unknown patches {sorted(unknown)}")
        volumes = [t for _, t in gmsh.model.getEntities(3)]
        gmsh.model.addPhysicalGroup(3, volumes, name="silo")
        if dump_geometry is not None:
            self.dump(dump_geometry)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as exc:
            raise self.fail(f"gmsh failed: {exc}") from exc
        if node_map is not None:
            map_nodes(node_map)
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)  # gmshToFoam reads ASCII only
        gmsh.write(str(self.msh_file))

    def element_kinds(self) -> dict[str, int]:
        """Count the 3D elements of each kind in the generated mesh."""
        names = {4: "tetrahedra", 5: "hexahedra", 6: "prisms", 7: "pyramids"}
        out: dict[str, int] = {}
        types, tags, _ = gmsh.model.mesh.getElements(3)
        for t, tg in zip(types, tags, strict=True):
            name = names.get(int(t), f"type{int(t)}")
            out[name] = out.get(name, 0) + len(tg)
        return out


def map_nodes(transform: Callable[[float, float, float], tuple[float, float, float]]) -> None:
    """Move every mesh node of the open model through ``transform`` (x, y, z) -> (x', y', z')."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    for k, tag in enumerate(tags):
        x, y, z = coords[3 * k : 3 * k + 3]
        gmsh.model.mesh.setNode(int(tag), list(transform(float(x), float(y), float(z))), [])
