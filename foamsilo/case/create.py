"""Write an OpenFOAM case for a scene: dictionaries, mesh and initial fill, whole or not at all.

The case is assembled in a hidden temporary directory beside the target
(``.NAME.foamsilo-tmp-PID-XXXX``) and renamed into place only when
complete, so a failure (a bad value caught late, gmsh, checkMesh, Ctrl-C)
leaves nothing half-written behind; a temporary directory left by a
process killed with ``kill -9`` is removed by the next case written there.
A case is a normal OpenFOAM case: ``siloFoam`` runs in it by hand, ParaView
opens ``case.foam``, and ``scene.toml`` holds the scene it came from.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo import __version__
from foamsilo.case.lifecycle import (
    METADATA_FILE,
    SCENE_FILE,
    CaseState,
    inspect,
    lock_holder,
    read_metadata,
)
from foamsilo.case.templates import render_templates
from foamsilo.errors import CaseStateError, MeshError, UsageError
from foamsilo.foam import check_mesh, run_utility, set_alpha_field, topo_set
from foamsilo.mesh import MeshResult, mesh_case
from foamsilo.scene import Scene, load_scene_file, scene_digest, to_toml
from foamsilo.toolchain import OpenFOAM

_TMP_MARK = ".foamsilo-tmp-"
#: Makes a case's mesh (and the field entries of its patches); default: the scene's gmsh mesh
Mesher = Callable[[Scene, Path, OpenFOAM], MeshResult]
#: What OpenFOAM accepts in a path: its file names are words without
#: whitespace, quotes or other characters its parser treats specially
_FOAM_PATH = re.compile(r"[A-Za-z0-9/._+=@,~%-]*")


@dataclass
class Case:
    """A written case.

    Attributes
    ----------
    path
        The case directory.
    scene
        The scene it was made from.
    representation
        ``planar``, ``axisymmetric`` or ``3d``.
    files
        Every file written, relative to ``path``.
    mesh
        Meshing result (cells, checkMesh figures).
    """

    path: Path
    scene: Scene
    representation: str
    files: list[str] = field(default_factory=list)
    mesh: MeshResult | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        return {
            "case_dir": str(self.path),
            "representation": self.representation,
            "files": self.files,
            "mesh": self.mesh.as_dict() if self.mesh else None,
        }


def write_whole(path: Path, text: str) -> None:
    """Write a file whole or not at all (a temporary file, then a rename)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def _list_files(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


def check_case_path(path: Path, option: str = "--output") -> Path:
    """Refuse, before anything is written, a case path OpenFOAM or the system cannot use.

    Returns the absolute path.

    Raises
    ------
    UsageError
        The path holds characters OpenFOAM cannot read (spaces, quotes,
        non-ASCII), is a file or lies under one, or cannot be created.
    """
    path = Path(os.path.abspath(path))
    bad = next((c for c in str(path) if not _FOAM_PATH.fullmatch(c)), None)
    if bad is not None:
        pos = str(path).index(bad)
        raise UsageError(
            option,
            f"{str(path)!r}: OpenFOAM cannot use {bad!r} (position {pos}) in a case path; its "
            "file names are ASCII words without spaces, quotes or other punctuation; allowed: "
            "letters, digits and / . _ + = @ , ~ % -",
        )
    for parent in [path, *path.parents]:
        if parent.exists():
            if not parent.is_dir():
                where = "is a file" if parent == path else f"lies under the file {parent}"
                raise UsageError(option, f"{path} {where}, not a directory")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise UsageError(option, f"cannot write in {parent} (permission denied)")
            break
    return path


def _make_parents(path: Path, option: str) -> list[Path]:
    """Create the missing parents of ``path``; return those created (outermost first)."""
    missing = []
    for parent in path.parents:
        if parent.exists():
            break
        missing.append(parent)
    missing.reverse()
    try:
        for p in missing:
            p.mkdir(exist_ok=True)  # another process may make it at the same moment
    except OSError as exc:
        _remove_created(missing)
        raise UsageError(option, f"cannot create {path.parent}: {exc.strerror}") from None
    return missing


def _remove_created(created: list[Path]) -> None:
    for p in reversed(created):
        with contextlib.suppress(OSError):
            p.rmdir()  # only if still empty


def remove_stale_temporaries(parent: Path, name: str) -> list[Path]:
    """Remove the temporary case directories a killed process left for ``name``."""
    from foamsilo.case.lifecycle import _pid_alive

    removed: list[Path] = []
    if not parent.is_dir():
        return removed
    for p in parent.glob(f".{name}{_TMP_MARK}*"):
        try:
            pid = int(p.name[len(f".{name}{_TMP_MARK}") :].split("-", 1)[0])
        except ValueError:
            continue
        if pid != os.getpid() and not _pid_alive(pid):
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


def _finish_case(scene: Scene, case: Path, of: OpenFOAM) -> None:
    """Return the steps after meshing: pristine fields, the initial fill, the zones."""
    if not (case / "0.orig").exists():
        shutil.copytree(case / "0", case / "0.orig")  # pristine fields, before the fill
    set_alpha_field(of, case)
    if scene.gas_coupled:
        topo_set(of, case)  # the zone the pore-pressure gradient is averaged on


def create_case(
    scene: Scene,
    case_dir: Path,
    of: OpenFOAM,
    *,
    overwrite: bool = False,
    scene_text: str | None = None,
    dump_geometry: Path | None = None,
    mesher: Mesher | None = None,
    metadata: dict[str, Any] | None = None,
) -> Case:
    """Write a complete, runnable case for ``scene`` at ``case_dir``.

    Parameters
    ----------
    scene
        The validated scene.
    case_dir
        Target directory; must not exist, or be empty, or (with ``overwrite``)
        be a foamsilo case that is not running.
    of
        OpenFOAM to run the mesh utilities with.
    overwrite
        Replace an existing foamsilo case (never a directory that is not one).
    scene_text
        Text of the scene file it came from (copied into the case); by
        default the validated scene is written.
    dump_geometry
        Also write the gmsh geometry there.
    mesher
        Makes the mesh instead of the scene's gmsh silo (the verification
        channel, :mod:`foamsilo.case.channel`), after the templates are
        rendered and before the initial fill.
    metadata
        More entries for ``foamsilo.json`` (what ``rebuild_mesh`` needs to
        make a mesher's mesh again).

    Raises
    ------
    UsageError
        The path cannot hold a case (see :func:`check_case_path`).
    CaseStateError
        The target is a case (without ``overwrite``), a running case, or a
        directory with files that is not a case.
    MeshError, FoamError
        Meshing or an OpenFOAM utility failed (the geometry is then kept
        beside the target for inspection).
    """
    case_dir = check_case_path(case_dir)
    status = inspect(case_dir)
    if status.state is CaseState.NEW and status.foreign:
        raise CaseStateError(case_dir, "not a case", status.advice())
    if status.state is CaseState.RUNNING:
        raise CaseStateError(case_dir, "running", status.advice())
    if status.state is not CaseState.NEW and not overwrite:
        raise CaseStateError(
            case_dir,
            status.state.value,
            f"{case_dir} holds a foamsilo case ({status.state.value}): --overwrite replaces it, "
            "or choose another directory",
        )
    created = _make_parents(case_dir, "--output")
    remove_stale_temporaries(case_dir.parent, case_dir.name)
    try:
        prefix = f".{case_dir.name}{_TMP_MARK}{os.getpid()}-"
        tmp = Path(tempfile.mkdtemp(prefix=prefix, dir=case_dir.parent))
    except OSError as exc:  # /proc, /sys, a read-only mount: writable in name only
        _remove_created(created)
        raise UsageError("--output", f"cannot create {case_dir}: {exc.strerror}") from None
    tmp.chmod(0o755)  # mkdtemp makes it private
    try:
        render_templates(scene, tmp)
        (tmp / SCENE_FILE).write_text(
            scene_text if scene_text is not None else to_toml(scene.to_dict())
        )
        (tmp / "case.foam").touch()
        try:
            mesh = mesher(scene, tmp, of) if mesher else mesh_case(scene, tmp, of, dump_geometry)
        except MeshError as exc:
            if exc.geometry_file and exc.geometry_file.exists():
                kept = case_dir.parent / f"{case_dir.name}.failed{exc.geometry_file.suffix}"
                shutil.copy(exc.geometry_file, kept)
                raise MeshError(str(exc).split(" (geometry written")[0], kept) from None
            raise
        _finish_case(scene, tmp, of)
        meta = {
            "foamsilo_version": __version__,
            "scene": scene.name,
            "scene_digest": scene_digest(scene),
            "representation": scene.representation,
            "cells": mesh.cells,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
            **(metadata or {}),
        }
        meta["files"] = sorted([*_list_files(tmp), METADATA_FILE])
        (tmp / METADATA_FILE).write_text(json.dumps(meta, indent=2))
        if case_dir.exists():
            if lock_holder(case_dir) is not None:  # started while this one was meshing
                raise CaseStateError(case_dir, "running", inspect(case_dir).advice())
            trash = case_dir.with_name(f".{case_dir.name}{_TMP_MARK}{os.getpid()}-old")
            case_dir.rename(trash)
            tmp.rename(case_dir)
            shutil.rmtree(trash, ignore_errors=True)
        else:
            tmp.rename(case_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        _remove_created(created)
        raise
    mesh.msh_file = case_dir / mesh.msh_file.relative_to(tmp)
    return Case(case_dir, scene, scene.representation, _list_files(case_dir), mesh)


def rebuild_mesh(case_dir: Path, of: OpenFOAM) -> MeshResult:
    """Mesh a case again from its own ``scene.toml`` (its ``constant/polyMesh`` was lost).

    gmsh is deterministic: the mesh is the one the case was made with, so
    its time directories still fit it.
    """
    case_dir = Path(case_dir)
    meta = read_metadata(case_dir)
    scene = load_scene_file(case_dir / SCENE_FILE)
    shutil.rmtree(case_dir / "constant" / "polyMesh", ignore_errors=True)
    from foamsilo.case.channel import CHANNEL_KEY

    if CHANNEL_KEY in meta:  # a channel: blockMesh from the case's own blockMeshDict
        from foamsilo.foam import block_mesh

        block_mesh(of, case_dir)
        return MeshResult(scene.representation, int(meta["cells"]), check_mesh(of, case_dir),
                          case_dir / "system" / "blockMeshDict", 0.0)  # fmt: skip
    mesh = mesh_case(scene, case_dir, of)
    if scene.gas_coupled:
        run_utility(of, case_dir, "topoSet")
    return mesh
