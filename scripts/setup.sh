#!/usr/bin/env bash
# Set up everything foamsilo needs on Debian 12, idempotently:
#   1. system packages: OpenFOAM v1912 (Debian's `openfoam`), a C++ compiler,
#      make, Open MPI headers, python3-venv -- only those that are missing;
#   2. OpenFOAM's headers and wmake from Debian's source package of the same
#      version, unpacked into the cache ($FOAMSILO_CACHE, default
#      ~/.cache/foamsilo), wmake built and src/*/lnInclude linked;
#   3. a Python virtual environment .venv with foamsilo (editable) and its
#      dependencies, reinstalled only when pyproject.toml changed.
# A user who sourced an OpenFOAM environment (WM_PROJECT_DIR set) keeps it:
# steps 1 (OpenFOAM part) and 2 are skipped.
# A second run skips everything that is done and returns within seconds.
set -euo pipefail

# Debian's own etc/bashrc sets WM_PROJECT_DIR without headers: not a user build
if [ "${WM_PROJECT_DIR:-}" = /usr/share/openfoam ]; then unset WM_PROJECT_DIR; fi

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache=${FOAMSILO_CACHE:-$HOME/.cache/foamsilo}
say() { printf '[foamsilo setup] %s\n' "$*" >&2; }

if [ "$(id -u)" = 0 ]; then SUDO=""; else SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

# ---------------------------------------------------------------- 1. packages
pkgs=()
if [ -z "${WM_PROJECT_DIR:-}" ]; then
    [ -x /usr/bin/interFoam ] || pkgs+=(openfoam)
    command -v mpicc >/dev/null 2>&1 || pkgs+=(libopenmpi-dev)
fi
command -v g++ >/dev/null 2>&1 || pkgs+=(g++)
command -v make >/dev/null 2>&1 || pkgs+=(make)
command -v bzip2 >/dev/null 2>&1 || pkgs+=(bzip2)
python3 -c 'import venv, ensurepip' >/dev/null 2>&1 || pkgs+=(python3-venv)
if [ ${#pkgs[@]} -gt 0 ]; then
    say "installing Debian packages: ${pkgs[*]}"
    $SUDO apt-get update -q
    $SUDO apt-get install -y -q --no-install-recommends "${pkgs[@]}"
fi

# ------------------------------------------------ 2. OpenFOAM headers + wmake
if [ -z "${WM_PROJECT_DIR:-}" ]; then
    version=$(sed -n 's/^export WM_PROJECT_VERSION=\(.*\)$/\1/p' /usr/share/openfoam/etc/bashrc)
    srcroot="$cache/openfoam-$version-src"
    if ! ls "$srcroot"/*/.foamsilo-headers-ready >/dev/null 2>&1; then
        say "fetching OpenFOAM $version sources (Debian source package) into $srcroot"
        if ! apt-get source --print-uris openfoam >/dev/null 2>&1; then
            say "adding a deb-src entry for bookworm main"
            $SUDO tee /etc/apt/sources.list.d/foamsilo-deb-src.sources >/dev/null <<'EOF'
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: bookworm
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
            $SUDO apt-get update -q
        fi
        rm -rf "$srcroot"
        mkdir -p "$srcroot/download"
        debver=$(dpkg-query -W -f='${source:Version}' openfoam)
        (cd "$srcroot/download" &&
            { apt-get source --download-only "openfoam=$debver" >/dev/null 2>&1 ||
              apt-get source --download-only openfoam >/dev/null; })
        tar -xjf "$srcroot"/download/openfoam_*.orig.tar.bz2 -C "$srcroot"
        rm -rf "$srcroot/download"
        tree=$(ls -d "$srcroot"/openfoam-*/ | head -n1)
        tree=${tree%/}
        rm -rf "$tree/tutorials" "$tree/doc"   # 144 MB not needed to build
        say "building wmake and linking headers in $tree"
        (
            export WM_PROJECT=OpenFOAM WM_PROJECT_VERSION="$version" WM_PROJECT_DIR="$tree"
            export WM_DIR="$tree/wmake" WM_ARCH=linux64 WM_COMPILER=Gcc WM_COMPILER_TYPE=system
            export WM_PRECISION_OPTION=DP WM_LABEL_SIZE=32 WM_COMPILE_OPTION=Opt
            export WM_OPTIONS=linux64GccDPInt32Opt WM_MPLIB=SYSTEMOPENMPI WM_OSTYPE=POSIX
            export PATH="$tree/wmake:$PATH"
            cd "$tree/wmake/src" && make -s >/dev/null
            cd "$tree/src" && wmakeLnIncludeAll . >/dev/null
        )
        touch "$tree/.foamsilo-headers-ready"
    fi
fi

# ------------------------------------------------------------- 3. Python venv
venv="$here/.venv"
stamp="$venv/.foamsilo-installed"
want=$(sha256sum "$here/pyproject.toml" | cut -d' ' -f1)
if [ ! -x "$venv/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    say "creating the Python environment $venv"
    [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
    log="$venv/pip-install.log"
    if ! { "$venv/bin/python" -m pip install --upgrade pip &&
           "$venv/bin/python" -m pip install -e "$here[test]"; } >"$log" 2>&1; then
        tail -n 40 "$log" >&2
        say "pip install failed (full log: $log)"
        exit 1
    fi
    echo "$want" > "$stamp"
fi
say "ready (OpenFOAM: ${WM_PROJECT_DIR:-Debian package}; venv: $venv)"
