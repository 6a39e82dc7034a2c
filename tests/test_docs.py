"""The documentation site builds with ``mkdocs build --strict`` (the ``docs`` extra).

Strict mode fails on any warning: a broken link or anchor between pages, a page missing
from the navigation, a docstring mkdocstrings cannot parse as numpydoc. The built HTML is
then read: the API pages hold the public functions with their parameters, no page shows a
docstring's reST role as text (``:class:`X``` must render as a link or as code), the
commands reference holds every sub-command's ``--help``, the axis reference every key,
and the guide's pages stay short.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
ROLE = re.compile(r":(?:py:)?(?:class|func|meth|attr|data|mod|obj|exc|const):`?")


class _Text(HTMLParser):
    """The text a reader sees (scripts and styles left out)."""

    def __init__(self) -> None:
        super().__init__()
        self.parts: list[str] = []
        self._skip = 0

    def handle_starttag(self, tag, attrs):
        self._skip += tag in ("script", "style")

    def handle_endtag(self, tag):
        self._skip -= tag in ("script", "style")

    def handle_data(self, data):
        if not self._skip:
            self.parts.append(data)


def visible_text(html: str) -> str:
    parser = _Text()
    parser.feed(html)
    return "".join(parser.parts)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    pytest.importorskip("mkdocstrings", reason="the docs extra builds the documentation")
    site = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
         "-d", str(site)],
        cwd=ROOT, capture_output=True, text=True, timeout=600, env=env,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-4000:]
    return site


def page(site: Path, name: str) -> str:
    path = site / ("index.html" if name == "index" else f"{name}/index.html")
    assert path.is_file(), name
    return path.read_text(encoding="utf-8")


def test_mkdocs_build_strict(site: Path):
    scoring = page(site, "api/scoring")
    assert 'id="vfgym.scoring.evaluate"' in scoring
    assert "Parameters" in scoring and "Returns" in scoring
    for name in ("index", "guide/sweep", "guide/fit", "guide/train", "guide/evaluate",
                 "reference/commands", "reference/axis", "model", "results", "results/tuning",
                 "results/fit", "results/agents", "results/speed", "results/tried"):  # fmt: skip
        page(site, name)


def test_visible_text_has_the_role_pattern_when_a_role_is_raw():
    """The check below sees a role as it rendered before the Griffe extension."""
    raw = "<p>as a <code>Score</code>; :func:<code>evaluate</code> runs</p>"
    raw += '<script>":class:"</script>'
    assert ROLE.findall(visible_text(raw)) == [":func:"]
    assert not ROLE.findall(visible_text('<p>a <a href="#x"><code>Score</code></a></p>'))


def test_no_page_shows_a_raw_rest_role(site: Path):
    shown = {}
    for path in sorted(site.rglob("*.html")):
        text = visible_text(path.read_text(encoding="utf-8"))
        found = ROLE.findall(text) + re.findall(r"</?autoref\b", text)  # or one left unresolved
        if found:
            shown[str(path.relative_to(site))] = len(found)
    assert not shown, f"raw reST roles in the built pages: {shown}"


def test_roles_render_as_links_to_the_objects(site: Path):
    """``:class:`Score``` in vfgym.scoring's docstring links to Score's anchor; across the
    API pages most roles resolve (the rest name objects the pages do not render)."""
    scoring = page(site, "api/scoring")
    assert re.search(r'<a class="autorefs autorefs-internal role"[^>]*href="#vfgym\.scoring\.Score"'
                     r"[^>]*><code>Score</code></a>", scoring)  # fmt: skip
    params = page(site, "api/params")
    # :attr:`Plant.torque_per_count_nm` in Servo's docstring: resolved in its module
    assert re.search(r'href="#vfgym\.params\.Plant\.torque_per_count_nm"[^>]*>'
                     r"<code>Plant\.torque_per_count_nm</code>", params)  # fmt: skip
    api = "".join(p.read_text(encoding="utf-8") for p in (site / "api").rglob("*.html"))
    linked = len(re.findall(r'class="autorefs autorefs-internal role"', api))
    assert linked >= 250, linked


def test_commands_reference_holds_every_subcommands_help(site: Path):
    from vfgym.cli import build_parser

    text = visible_text(page(site, "reference/commands"))
    subs = build_parser().subcommands
    assert "fit" in subs
    for name in subs:
        assert f"usage: vfgym {name} " in text, name
    assert "usage: vfgym [-h] [--version]" in text


def test_axis_reference_lists_every_key(site: Path):
    import dataclasses

    import vfgym
    from vfgym.moves.distribution import MoveDistribution

    html = page(site, "reference/axis")
    for cls in (vfgym.Plant, vfgym.Motor, vfgym.Servo, vfgym.Measures, vfgym.Scenario,
                MoveDistribution):  # fmt: skip
        for f in dataclasses.fields(cls):
            if f.init:
                assert f"<code>{f.name}</code>" in html, (cls.__name__, f.name)


def test_the_reference_pages_hold_what_the_code_says():
    """The generated blocks of the reference pages (every ``--help``, every axis key) are
    in the repository's files as the code writes them today (``docs/_reference.py``), and
    the commands table has a row for every sub-command."""
    import runpy

    from vfgym.cli import build_parser

    ref = runpy.run_path(str(DOCS / "_reference.py"))
    for name, path in ref["BLOCKS"].items():
        text = path.read_text(encoding="utf-8")
        assert ref["with_block"](text, name, ref["generated"](name)) == text, (
            f"{path.name} differs from the code: run python docs/_reference.py"
        )
    table = (DOCS / "reference" / "commands.md").read_text(encoding="utf-8").split("\n\n")
    rows = next(part for part in table if part.startswith("| command |"))
    for name in build_parser().subcommands:
        assert f"| `vfgym {name} " in rows, name
    # the check finds a block that differs
    stale = ref["with_block"]("x\n<!-- vfgym:help:begin -->\nold\n<!-- vfgym:help:end -->\n",
                              "help", "new")  # fmt: skip
    assert stale == "x\n<!-- vfgym:help:begin -->\nnew\n<!-- vfgym:help:end -->\n"


def test_guide_pages_are_short():
    pages = sorted((DOCS / "guide").glob("*.md"))
    assert len(pages) >= 4
    lines = {p.name: len(p.read_text(encoding="utf-8").splitlines()) for p in pages}
    long = {name: n for name, n in lines.items() if n > 250}
    assert not long, long


def test_every_figure_is_on_a_page():
    """Each image in docs/images is shown or named by a page (moved, not lost)."""
    text = "".join(p.read_text(encoding="utf-8") for p in DOCS.rglob("*.md"))
    for image in sorted((DOCS / "images").glob("*.png")):
        assert f"images/{image.name}" in text, image.name


def test_the_servo_interval_is_stated_as_shipped():
    """README and the training guide give VFServo-v0's default control interval and the
    one the shipped hyperparameter files train with, as those files and the env say."""
    import yaml

    from vfgym.envs._common import SERVO_INTERVAL_S

    files = sorted((ROOT / "src/vfgym/agents/hyperparams_files").glob("*.yml"))
    shipped = {
        yaml.safe_load(f.read_text(encoding="utf-8"))["vfgym/VFServo-v0"]["env_kwargs"][
            "interval_s"
        ]
        for f in files
    }
    assert len(files) == 4 and len(shipped) == 1  # ppo, sac, td3, ppo_lstm
    default_ms, shipped_ms = SERVO_INTERVAL_S * 1e3, shipped.pop() * 1e3
    for name in ("README.md", "docs/guide/train.md"):
        text = " ".join((ROOT / name).read_text(encoding="utf-8").split()).replace("*", "")
        assert re.search(rf"(?<![\d.]){default_ms:g} ms by default", text), name
        assert re.search(rf"(?<![\d.]){shipped_ms:g} ms", text), name
