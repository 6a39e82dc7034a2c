"""What ``vfgym predict --help`` says the shipped settings model is."""

from __future__ import annotations

from vfgym.cli import main


def test_predict_help_names_the_neighbour_lookup(capsys):
    assert main(["predict", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "neighbour look-up" in text
    assert "regression" not in text
