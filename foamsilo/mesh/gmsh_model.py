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
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import gmsh
import numpy as np

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


@dataclass(frozen=True)
class Carve:
    """A shape cut out of patch ``source``: the rest of its faces go to patch ``target``.

    The faces kept are those nearest the shape's centre (``distance`` of
    their centres, an (n, 3) array, in the shape's own norm) whose areas add
    up closest to ``area``: the cut holds the shape's area to within half a
    face, whatever the cells. ``name`` says what the shape is (in errors).
    """

    source: str
    target: str
    distance: Callable[[np.ndarray], np.ndarray]
    area: float
    name: str


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
        carve: Carve | None = None,
    ) -> None:
        """Mesh; add one physical group per patch (in ``patch_order``) and the volume; write.

        ``node_map`` moves every node of the generated mesh before it is
        written (a hopper meshed as a cylinder, then mapped onto its cone).
        ``carve`` moves the faces of one patch that lie outside a shape to
        another patch (a circular hole cut out of a rectangle of wall faces).

        Raises
        ------
        MeshError
            A patch has no surface, or gmsh failed to mesh (geometry dumped).
        """
        for name in patch_order:
            if not self.patches.get(name):
                raise self.fail(f"no surface for patch {name!r}")
        unknown = set(self.patches) - set(patch_order)
        if unknown:
            raise self.fail(f"surfaces recorded for unknown patches {sorted(unknown)}")
        if dump_geometry is not None:
            self.dump(dump_geometry)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as exc:
            raise self.fail(f"gmsh failed: {exc}") from exc
        if carve is not None:
            self._carve(carve)
        for name in patch_order:
            gmsh.model.addPhysicalGroup(2, sorted(set(self.patches[name])), name=name)
        volumes = [t for _, t in gmsh.model.getEntities(3)]
        gmsh.model.addPhysicalGroup(3, volumes, name="silo")
        if node_map is not None:
            map_nodes(node_map)
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)  # gmshToFoam reads ASCII only
        gmsh.write(str(self.msh_file))

    def _carve(self, carve: Carve) -> None:
        """Keep the faces of ``carve.source`` that make up the shape; move the rest to ``target``.

        The faces that leave go to a new discrete surface each (gmsh keeps
        their nodes), recorded in the target patch.

        Raises
        ------
        MeshError
            The source patch's faces cannot hold the shape's area.
        """
        blocks = []  # (entity, element type, tags, node tags, distances, areas)
        for ent in sorted(set(self.patches[carve.source])):
            for typ in gmsh.model.mesh.getElementTypes(2, ent):
                got_tags, got_nodes = gmsh.model.mesh.getElementsByType(typ, ent)
                conn = np.asarray(got_nodes).reshape(len(got_tags), -1)
                centres = np.asarray(gmsh.model.mesh.getBarycenters(typ, ent, False, True))
                near = np.asarray(carve.distance(centres.reshape(-1, 3)), dtype=float)
                blocks.append((ent, typ, np.asarray(got_tags), conn, near, _face_areas(conn)))
        dist = np.concatenate([b[4] for b in blocks])
        areas = np.concatenate([b[5] for b in blocks])
        order = np.argsort(dist, kind="stable")
        total = np.cumsum(areas[order])
        if total[-1] < carve.area:
            raise self.fail(f"the faces of patch {carve.source!r} cannot hold the {carve.name}")
        k = int(np.argmin(np.abs(total - carve.area))) + 1
        keep = np.zeros(len(dist), dtype=bool)
        keep[order[:k]] = True
        moved: list[int] = []
        start = 0
        for ent, typ, etags, enodes, d, _ in blocks:
            inside = keep[start : start + len(d)]
            start += len(d)
            if inside.all():
                continue
            gmsh.model.mesh.removeElements(2, ent, etags[~inside].tolist())
            new = gmsh.model.addDiscreteEntity(2)
            gmsh.model.mesh.addElements(2, new, [typ], [etags[~inside].tolist()],
                                        [enodes[~inside].ravel().tolist()])  # fmt: skip
            moved.append(new)
        self.patches.setdefault(carve.target, []).extend(moved)

    def element_kinds(self) -> dict[str, int]:
        """Count the 3D elements of each kind in the generated mesh."""
        names = {4: "tetrahedra", 5: "hexahedra", 6: "prisms", 7: "pyramids"}
        out: dict[str, int] = {}
        types, tags, _ = gmsh.model.mesh.getElements(3)
        for t, tg in zip(types, tags, strict=True):
            name = names.get(int(t), f"type{int(t)}")
            out[name] = out.get(name, 0) + len(tg)
        return out


def _face_areas(conn: np.ndarray) -> np.ndarray:
    """Areas of the mesh's faces with these node tags (one row per face; fan triangles)."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    where = {int(t): i for i, t in enumerate(tags)}
    xyz = np.asarray(coords).reshape(-1, 3)[[where[int(n)] for n in conn.ravel()]]
    xyz = xyz.reshape(conn.shape[0], conn.shape[1], 3)
    area = np.zeros(conn.shape[0])
    for i in range(1, conn.shape[1] - 1):
        a, b = xyz[:, i] - xyz[:, 0], xyz[:, i + 1] - xyz[:, 0]
        area += 0.5 * np.linalg.norm(np.cross(a, b), axis=1)
    return area


def map_nodes(transform: Callable[[float, float, float], tuple[float, float, float]]) -> None:
    """Move every mesh node of the open model through ``transform`` (x, y, z) -> (x', y', z')."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    for k, tag in enumerate(tags):
        x, y, z = coords[3 * k : 3 * k + 3]
        gmsh.model.mesh.setNode(int(tag), list(transform(float(x), float(y), float(z))), [])
