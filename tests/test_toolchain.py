"""Which OpenFOAM is used: a sourced user environment takes precedence."""

from __future__ import annotations

import pytest

from foamsilo import toolchain
from foamsilo.errors import ToolchainError


def fake_install(tmp_path):
    root = tmp_path / "OpenFOAM-v2312"
    (root / "platforms/bin").mkdir(parents=True)
    (root / "platforms/bin/interFoam").write_text("")
    (root / "src/finiteVolume/lnInclude").mkdir(parents=True)
    (root / "src/finiteVolume/lnInclude/fvCFD.H").write_text("")
    return root


def test_user_environment_wins(tmp_path, monkeypatch):
    root = fake_install(tmp_path)
    monkeypatch.setenv("WM_PROJECT_DIR", str(root))
    monkeypatch.setenv("WM_PROJECT_VERSION", "v2312")
    monkeypatch.setenv("FOAM_APPBIN", str(root / "platforms/bin"))
    monkeypatch.setenv("WM_OPTIONS", "linux64GccDPInt32Opt")
    of = toolchain.find_openfoam()
    assert of.source == "user-environment"
    assert of.version == "v2312"
    assert of.appbin == root / "platforms/bin"
    assert of.has_headers
    env = of.build_env(tmp_path / "bin", tmp_path / "lib")
    assert env["WM_PROJECT_DIR"] == str(root)  # untouched
    assert env["FOAM_USER_APPBIN"] == str(tmp_path / "bin")


def test_debian_bashrc_is_still_the_debian_package(monkeypatch):
    monkeypatch.setenv("WM_PROJECT_DIR", str(toolchain.DEBIAN_ETC))
    if toolchain._debian_version() is None:
        with pytest.raises(ToolchainError):
            toolchain.find_openfoam()
    else:
        assert toolchain.find_openfoam().source == "debian-package"


def test_nothing_installed_names_the_fix(monkeypatch, tmp_path):
    monkeypatch.delenv("WM_PROJECT_DIR", raising=False)
    monkeypatch.setattr(toolchain, "DEBIAN_ETC", tmp_path / "none")
    with pytest.raises(ToolchainError) as exc:
        toolchain.find_openfoam()
    assert exc.value.fix == toolchain.SETUP_COMMAND
    assert "OpenFOAM" in str(exc.value)


def test_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("FOAMSILO_CACHE", str(tmp_path))
    assert toolchain.cache_dir() == tmp_path
