"""The front door and the pages behind it: the README stays short, every link in it and in docs/ resolves (files and
headings), and every code block is run or checked by a test (the kinds below); the output the README shows is what
the quickstart's first command prints."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import ROOT

MAX_README_LINES = 250
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: How each kind of code block is kept true: python blocks by tests/test_readme_names.py (every name imports) and
#: tests/test_readme.py (the README's and the API page's first run); bash blocks by the command-line parser here
#: (each ``op2motion`` line parses), the examples of docs/cli.md by tests/test_readme.py (run as written) and the
#: quickstart by .ci/run; the README's text block by the quickstart test below; the package map (a bare block in
#: docs/development.md) by tests/test_readme.py.
CHECKED_KINDS = {"python", "bash", "text", ""}


def _blocks(path: Path) -> list[tuple[str, str]]:
    """(language, code) of every fenced block of a page."""
    return re.findall(r"^```(\w*)\n(.*?)^```", path.read_text(encoding="utf-8"), re.S | re.M)


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation out, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def test_the_readme_is_a_front_door():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= MAX_README_LINES
    for part in ("## Quickstart", "## In Python", "## Commands", "## Where to go next", "Jong-Wook Kim"):
        assert part in text, part


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_link_resolves(page):
    text = page.read_text(encoding="utf-8")
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"\w+://", target):
            continue                                    # no network here; the pages link nothing outside
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        assert file.is_file(), f"{page.name}: {target}"
        if anchor:
            headings = re.findall(r"^#+ (.*)$", file.read_text(encoding="utf-8"), re.M)
            assert anchor in {_anchor(h) for h in headings}, f"{page.name}: {target}"


def test_every_code_block_is_of_a_checked_kind():
    kinds = {(page.name, lang) for page in PAGES for lang, _ in _blocks(page)}
    assert {lang for _, lang in kinds} <= CHECKED_KINDS, kinds
    bare = {name for name, lang in kinds if lang == ""}
    text = {name for name, lang in kinds if lang == "text"}
    assert bare <= {"development.md"} and text <= {"README.md"}, (bare, text)


def test_every_command_line_shown_parses():
    """Each ``op2motion ...`` line of a bash block parses with today's command line (the docs/cli.md examples also
    run, tests/test_readme.py)."""
    from op2motion.cli import build_parser

    parser = build_parser()
    lines = [line for page in PAGES for lang, code in _blocks(page) if lang == "bash"
             for line in code.splitlines() if line.startswith("op2motion ")]
    assert len(lines) >= 15
    for line in lines:
        parser.parse_args(shlex.split(line)[1:])


@pytest.mark.physics
def test_the_output_the_readme_shows_is_what_the_quickstart_prints(tmp_path):
    """The README's text block is the first quickstart command's output, figure for figure (the search's wall time
    aside), run in a scratch folder."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    shown = [code for lang, code in re.findall(r"^```(\w*)\n(.*?)^```", text, re.S | re.M) if lang == "text"][0]
    done = subprocess.run([sys.executable, "-m", "op2motion", "optimize", "--validate"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr

    def masked(lines: str) -> list[str]:
        return [re.sub(r"arm-ik, [\d.]+ s", "arm-ik, T s", line) for line in lines.strip().splitlines()]

    assert masked(done.stdout) == masked(shown)
