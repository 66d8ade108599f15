"""Find OpenFOAM, its headers and wmake, MPI and gmsh; build the environments.

Two sources of OpenFOAM are supported:

``user-environment``
    The user sourced an OpenFOAM ``etc/bashrc`` (``WM_PROJECT_DIR`` is set);
    that installation, its headers and its wmake are used as they are.
``debian-package``
    Debian's ``openfoam`` package (v1912, ESI): binaries in ``/usr/bin``,
    libraries in ``/usr/lib``, configuration in ``/usr/share/openfoam``.  It
    ships no headers and no wmake; ``scripts/setup.sh`` unpacks Debian's
    source package of the same version into the cache
    (``$FOAMSILO_CACHE``, default ``~/.cache/foamsilo``), builds wmake and
    links the headers (``wmakeLnIncludeAll``).
"""

from __future__ import annotations

import os
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from foamsilo.errors import ToolchainError

#: The command that installs every missing system piece (root, idempotent).
SETUP_COMMAND = "bash scripts/setup.sh"

DEBIAN_ETC = Path("/usr/share/openfoam")
DEBIAN_LIBBIN = Path("/usr/lib")
DEBIAN_APPBIN = Path("/usr/bin")
HEADERS_READY = ".foamsilo-headers-ready"


def cache_dir() -> Path:
    """Cache outside the clone: OpenFOAM sources and solver builds."""
    return Path(os.environ.get("FOAMSILO_CACHE", Path.home() / ".cache" / "foamsilo"))


@dataclass(frozen=True)
class OpenFOAM:
    """An OpenFOAM installation and how to use it.

    Attributes
    ----------
    source
        ``"user-environment"`` or ``"debian-package"``.
    version
        ``WM_PROJECT_VERSION``, e.g. ``"v1912"``.
    project_dir
        ``WM_PROJECT_DIR`` to run the binaries with.
    appbin
        Directory of the OpenFOAM binaries.
    source_dir
        Tree with ``src/*/lnInclude`` and ``wmake`` for building, or None
        when the headers are not set up.
    """

    source: str
    version: str
    project_dir: Path
    appbin: Path
    source_dir: Path | None

    @property
    def has_headers(self) -> bool:
        """Whether headers and wmake are there to build the solver."""
        if self.source_dir is None:
            return False
        return (self.source_dir / "src/OpenFOAM/lnInclude/fvCFD.H").exists() or (
            self.source_dir / "src/finiteVolume/lnInclude/fvCFD.H"
        ).exists()

    @property
    def wm_options(self) -> str:
        """Build options string (the ABI the solver is built for)."""
        if self.source == "user-environment":
            return os.environ.get("WM_OPTIONS", "unknown")
        return "linux64GccDPInt32Opt"

    def runtime_env(self) -> dict[str, str]:
        """Environment to run OpenFOAM binaries and utilities."""
        env = dict(os.environ)
        if self.source == "debian-package":
            env["WM_PROJECT_DIR"] = str(self.project_dir)
            env.setdefault("WM_PROJECT", "OpenFOAM")
            env.setdefault("WM_PROJECT_VERSION", self.version)
        if os.geteuid() == 0:
            # Open MPI refuses to run as root without these
            env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
            env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        # One thread per rank: MPI and BLAS-threaded numpy must not oversubscribe
        env.setdefault("OMP_NUM_THREADS", "1")
        # PyFoam's parallel runner picks the mpirun flavour from WM_MPLIB
        env.setdefault("WM_MPLIB", "SYSTEMOPENMPI")
        return env

    def build_env(self, user_appbin: Path, user_libbin: Path) -> dict[str, str]:
        """Environment for wmake, installing into the given directories."""
        if not self.has_headers or self.source_dir is None:
            raise ToolchainError(
                "OpenFOAM headers",
                "no OpenFOAM headers and wmake to build the solver",
                SETUP_COMMAND,
            )
        env = dict(os.environ)
        if self.source == "debian-package":
            src = self.source_dir
            env.update(
                WM_PROJECT="OpenFOAM",
                WM_PROJECT_VERSION=self.version,
                WM_PROJECT_DIR=str(src),
                WM_DIR=str(src / "wmake"),
                WM_ARCH="linux64",
                WM_ARCH_OPTION="64",
                WM_COMPILER="Gcc",
                WM_COMPILER_TYPE="system",
                WM_COMPILER_LIB_ARCH="64",
                WM_PRECISION_OPTION="DP",
                WM_LABEL_SIZE="32",
                WM_LABEL_OPTION="Int32",
                WM_COMPILE_OPTION="Opt",
                WM_OPTIONS=self.wm_options,
                WM_MPLIB="SYSTEMOPENMPI",
                WM_OSTYPE="POSIX",
                FOAM_MPI="openmpi-system",
                FOAM_SRC=str(src / "src"),
                FOAM_ETC=str(src / "etc"),
                FOAM_APP=str(src / "applications"),
                FOAM_SOLVERS=str(src / "applications/solvers"),
                FOAM_LIBBIN=str(DEBIAN_LIBBIN),
                FOAM_EXT_LIBBIN=str(DEBIAN_LIBBIN),
                FOAM_APPBIN=str(DEBIAN_APPBIN),
            )
            env["PATH"] = f"{src / 'wmake'}:{env.get('PATH', '')}"
        env["FOAM_USER_APPBIN"] = str(user_appbin)
        env["FOAM_USER_LIBBIN"] = str(user_libbin)
        return env


def debian_source_dir(version: str) -> Path | None:
    """Return the unpacked Debian source tree in the cache, if complete."""
    base = cache_dir() / f"openfoam-{version}-src"
    if not base.is_dir():
        return None
    for tree in sorted(base.iterdir()):
        if (tree / HEADERS_READY).exists():
            return tree
    return None


def _debian_version() -> str | None:
    bashrc = DEBIAN_ETC / "etc" / "bashrc"
    if not bashrc.exists() or not (DEBIAN_APPBIN / "interFoam").exists():
        return None
    m = re.search(r"^export WM_PROJECT_VERSION=(\S+)", bashrc.read_text(), re.M)
    return m.group(1) if m else "unknown"


def find_openfoam() -> OpenFOAM:
    """Locate the OpenFOAM to use: a sourced environment first, then Debian's.

    Raises
    ------
    ToolchainError
        When neither is there, with the command that installs it.
    """
    wm_dir = os.environ.get("WM_PROJECT_DIR")
    # Sourcing Debian's own etc/bashrc sets WM_PROJECT_DIR to its etc tree,
    # which has no headers: that is still the Debian package
    debian_env = wm_dir is not None and Path(wm_dir).resolve() == DEBIAN_ETC.resolve()
    if wm_dir and Path(wm_dir).is_dir() and not debian_env:
        appbin = Path(os.environ.get("FOAM_APPBIN", Path(wm_dir) / "bin"))
        if not (appbin / "interFoam").exists():
            found = shutil.which("interFoam")
            appbin = Path(found).parent if found else appbin
        return OpenFOAM(
            source="user-environment",
            version=os.environ.get("WM_PROJECT_VERSION", "unknown"),
            project_dir=Path(wm_dir),
            appbin=appbin,
            source_dir=Path(wm_dir),
        )
    version = _debian_version()
    if version is not None:
        return OpenFOAM(
            source="debian-package",
            version=version,
            project_dir=DEBIAN_ETC,
            appbin=DEBIAN_APPBIN,
            source_dir=debian_source_dir(version),
        )
    raise ToolchainError(
        "OpenFOAM",
        "no sourced OpenFOAM environment (WM_PROJECT_DIR) and no Debian openfoam package",
        SETUP_COMMAND,
    )


def mpi_info() -> dict[str, str | None]:
    """Return the path and version of mpirun (None when missing)."""
    from foamsilo.process import run_command

    path = shutil.which("mpirun")
    version = None
    if path:
        try:
            out = run_command([path, "--version"], env=dict(os.environ), timeout=20).output
            version = out.strip().splitlines()[0] if out.strip() else None
        except OSError:
            version = None
    return {"mpirun": path, "version": version}


def gmsh_version() -> str | None:
    """Version of the gmsh Python module, or None."""
    try:
        import gmsh
    except ImportError:  # pragma: no cover - a dependency
        return None
    return str(gmsh.__version__)
