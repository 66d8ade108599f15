"""Bad input through the command line: exit 2, the field named, nothing written."""

from __future__ import annotations

import json

import pytest

from foamsilo.cli import main


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ("silo.orifice_width=0.12", "silo.orifice_width"),
        ("silo.fill_height=1.0", "silo.fill_height"),
        ("silo.width=-0.1", "silo.width"),
        ("silo.nonsense=3", "silo.nonsense"),
    ],
)
def test_new_with_bad_scene_writes_nothing(tmp_path, capsys, override, field):
    out = tmp_path / "case"
    code = main(["new", "zhou-planar", "-o", str(out), "--set", override, "--json"])
    assert code == 2
    payload = json.loads(capsys.readouterr().out)
    assert payload["ok"] is False
    assert payload["error"]["field"] == field
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_bad_scene_file(tmp_path, capsys):
    f = tmp_path / "bad.toml"
    f.write_text('name = "x"\n[silo]\nwidth = "wide"\n')
    code = main(["mesh", str(f), "--json"])
    assert code == 2
    err = json.loads(capsys.readouterr().out)["error"]
    assert err["field"] == "silo.width"


def test_presets_json(capsys):
    assert main(["presets", "--json"]) == 0
    names = [p["name"] for p in json.loads(capsys.readouterr().out)["presets"]]
    assert "zhou-planar" in names


def test_scene_reference_is_markdown(capsys):
    assert main(["scene-reference"]) == 0
    assert "| `orifice_width` | m |" in capsys.readouterr().out


def test_json_mode_keeps_stray_prints_off_stdout(monkeypatch, capsys):
    """PyFoam prints (e.g. "Killing PID ...") while a run is stopped; with --json
    stdout must still hold exactly one JSON object."""

    import foamsilo.cli as cli

    def noisy(args):
        print("Killing PID 12345")  # what PyFoam's FoamThread prints
        cli._emit(args, {"ok": True, "x": 1}, lambda: None)
        return 0

    monkeypatch.setattr(cli, "cmd_presets", noisy)
    assert cli.main(["presets", "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out) == {"ok": True, "x": 1}
    assert "Killing PID" in err


def test_committed_cli_reference_is_current():
    from pathlib import Path

    from foamsilo.cli import cli_reference_markdown

    doc = Path(__file__).resolve().parent.parent / "docs" / "cli.md"
    assert doc.read_text().strip() == cli_reference_markdown().strip(), (
        "docs/cli.md is stale: foamsilo cli-reference > docs/cli.md"
    )
