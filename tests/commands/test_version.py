"""``vfgym --version`` prints the installed package's version and exits 0."""

from __future__ import annotations

from importlib.metadata import version

from vfgym.cli import main


def test_version_prints_the_package_metadata_version(capsys):
    assert main(["--version"]) == 0
    out = capsys.readouterr().out.strip()
    assert out == f"vfgym {version('vfgym')}"
    assert version("vfgym")[0].isdigit()


def test_version_needs_no_command_and_help_lists_it(capsys):
    assert main(["--help"]) == 0
    assert "--version" in capsys.readouterr().out
