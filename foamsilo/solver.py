"""Build the siloFoam solver and its mu(I) library with wmake, on demand.

The build lives in the cache outside the clone, in a directory named by a
hash of ``solver_src/`` and of the OpenFOAM it is built against, so it is
rebuilt exactly when a source file (or OpenFOAM) changed.  A build is
complete when its ``build.json`` exists; a file lock keeps concurrent runs
(tests, sweeps) from building the same thing twice.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import shutil
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from foamsilo.errors import FoamError, ToolchainError
from foamsilo.process import run_command
from foamsilo.resources import solver_source_dir
from foamsilo.toolchain import OpenFOAM, cache_dir, find_openfoam

#: Name of the solver application the cases run
SOLVER_NAME = "siloFoam"
LIB_NAME = "libfoamsiloViscosityModels.so"
_IGNORED_PARTS = {"lnInclude", "__pycache__"}
#: Python's marker of the data package, not a solver source
_IGNORED_FILES = {"__init__.py"}


def _source_files(src: Path) -> Iterator[Path]:
    for p in sorted(src.rglob("*")):
        rel = p.relative_to(src)
        if not p.is_file() or _IGNORED_PARTS & set(rel.parts) or rel.name in _IGNORED_FILES:
            continue
        # wmake build products live in Make/<WM_OPTIONS>/
        if len(rel.parts) >= 3 and rel.parts[-3] == "Make" or rel.suffix in {".o", ".dep"}:
            continue
        yield p


def source_hash(of: OpenFOAM) -> str:
    """Hash of the solver sources and the OpenFOAM they are built against."""
    src = solver_source_dir()
    h = hashlib.sha256()
    h.update(f"{of.source}|{of.version}|{of.wm_options}|{of.project_dir}".encode())
    for p in _source_files(src):
        h.update(str(p.relative_to(src)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


@dataclass(frozen=True)
class SolverBuild:
    """A complete solver build.

    Attributes
    ----------
    root
        Build directory in the cache.
    executable
        The ``siloFoam`` binary.
    library
        The mu(I) viscosity library.
    source_hash
        Hash it was built from.
    """

    root: Path
    executable: Path
    library: Path
    source_hash: str

    @property
    def info(self) -> dict[str, object]:
        """Contents of ``build.json``."""
        return json.loads((self.root / "build.json").read_text())


def _build_root(of: OpenFOAM) -> Path:
    return cache_dir() / "solver" / source_hash(of)


def find_solver(of: OpenFOAM | None = None) -> SolverBuild | None:
    """Return the build matching the current sources, or None if not built."""
    of = of or find_openfoam()
    root = _build_root(of)
    exe, lib = root / "bin" / SOLVER_NAME, root / "lib" / LIB_NAME
    if (root / "build.json").exists() and exe.exists() and lib.exists():
        return SolverBuild(root, exe, lib, root.name)
    return None


@contextmanager
def _lock(path: Path) -> Iterator[None]:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def ensure_solver(
    force: bool = False,
    of: OpenFOAM | None = None,
    log: Callable[[str], None] | None = None,
) -> SolverBuild:
    """Return the solver build, building it first if needed.

    Parameters
    ----------
    force
        Rebuild even if a build for the current sources exists.
    of
        OpenFOAM to build against (default: :func:`find_openfoam`).
    log
        Called with progress messages.

    Raises
    ------
    ToolchainError
        Headers or wmake missing.
    FoamError
        wmake failed; the output names the compiler error.
    """
    of = of or find_openfoam()
    say = log or (lambda _msg: None)
    root = _build_root(of)
    with _lock(root.with_suffix(".lock")):
        if not force:
            found = find_solver(of)
            if found is not None:
                return found
        env = of.build_env(root / "bin", root / "lib")
        if shutil.which("wmake", path=env["PATH"]) is None:
            raise ToolchainError("wmake", "wmake not found on PATH", "bash scripts/setup.sh")
        if root.exists():
            shutil.rmtree(root)
        build_src = root / "src"
        shutil.copytree(
            solver_source_dir(),
            build_src,
            ignore=shutil.ignore_patterns(
                "lnInclude", "linux64*", "*.o", "*.dep", "__pycache__", "__init__.py"
            ),
        )
        (root / "bin").mkdir()
        (root / "lib").mkdir()
        say(f"building {SOLVER_NAME} against OpenFOAM {of.version} ({of.source}) in {root}")
        t0 = time.perf_counter()
        res = run_command(["./Allwmake"], cwd=build_src, env=env)
        (root / "build.log").write_text(res.output)
        exe, lib = root / "bin" / SOLVER_NAME, root / "lib" / LIB_NAME
        if res.returncode != 0 or not exe.exists() or not lib.exists():
            errors = [ln for ln in res.output.splitlines() if "error" in ln]
            raise FoamError(
                "Allwmake (solver_src)",
                res.returncode or 1,
                "\n".join(errors[-20:]) or res.output[-4000:],
                build_src,
            )
        info = {
            "source_hash": root.name,
            "openfoam_version": of.version,
            "openfoam_source": of.source,
            "wm_options": of.wm_options,
            "build_seconds": round(time.perf_counter() - t0, 1),
            "built_at": time.strftime("%Y-%m-%dT%H:%M:%S"),
        }
        # Written last: its presence marks a complete build
        (root / "build.json").write_text(json.dumps(info, indent=2))
        say(f"built in {info['build_seconds']} s")
        return SolverBuild(root, exe, lib, root.name)
