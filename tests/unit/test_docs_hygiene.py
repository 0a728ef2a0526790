"""The repository cites only what is inside it, and its docs and comments carry no work-item talk.

Checked over every text file a user or contributor reads (Python sources and their comments and
strings, Markdown pages, the Makefile, mkdocs.yml, pyproject.toml, shell scripts):

- no citation of the project notes kept outside the repository (the design, algorithm, testing,
  style and anchor notes) or of the lab notebooks that were removed from it;
- no path outside the tree, except the public test scenes' default folder (`../shared/scenes`,
  which `$RESTIR_SCENES` overrides);
- every `docs/....md` or `docs/....py` path named anywhere exists (or is a page generated at build time);
- no work-item numbers or diary words ("issue 12", "stop 42", "this session").
"""
import pathlib
import re

from docgen.reference import PAGES

ROOT = pathlib.Path(__file__).resolve().parents[2]
FOLDERS = ("restir", "tests", "benchmarks", "gpu", "docgen", "docs")
TOP = ("README.md", "Makefile", "mkdocs.yml", "pyproject.toml", "restir_cli.py")
SUFFIXES = {".py", ".md", ".yml", ".yaml", ".toml", ".sh", ".txt"}

OUTSIDE_NOTES = re.compile(r"\b(ALGORITHMS|TESTING|DESIGN|STYLE|ANCHORS|BENCHMARKS|VALIDATION)\.md\b")
OUTSIDE_PATH = re.compile(r"\.\./shared(?!/scenes\b)|/work/")
WORK_ITEMS = re.compile(r"\b(issues?\s*#?\d+|stops?\s+\d+|the issue\b|(this|last|next|previous) session\b|"
                        r"sessions?\s+\d+|first look|second look|third look)", re.I)
# in Markdown, no diary words at all (in Python, pytest's scope="session" is code)
SESSION_IN_PROSE = re.compile(r"\bsessions?\b", re.I)
DOC_PATH = re.compile(r"\bdocs/[\w/.-]+?\.(?:md|py)\b")


def files():
    out = [ROOT / name for name in TOP if (ROOT / name).exists()]
    for folder in FOLDERS:
        for p in sorted((ROOT / folder).rglob("*")):
            if p.is_file() and p.suffix in SUFFIXES and "__pycache__" not in p.parts and "hostile" not in p.parts:
                out.append(p)
    return [p for p in out if p != pathlib.Path(__file__).resolve()]


def problems(name: str, text: str) -> list:
    """Every violation in one file's text, as 'name:line: what'."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        for pattern, what in ((OUTSIDE_NOTES, "cites a note outside the repository"),
                              (OUTSIDE_PATH, "names a path outside the repository"),
                              (WORK_ITEMS, "work-item words")):
            m = pattern.search(line)
            if m:
                out.append(f"{name}:{n}: {what}: {m.group(0)!r}")
        if name.endswith(".md") and SESSION_IN_PROSE.search(line):
            out.append(f"{name}:{n}: work-item words: {SESSION_IN_PROSE.search(line).group(0)!r}")
        for m in DOC_PATH.finditer(line):
            generated = m.group(0).removeprefix("docs/") in PAGES  # built from the code by mkdocs
            if not generated and not (ROOT / m.group(0)).exists():
                out.append(f"{name}:{n}: names {m.group(0)}, which does not exist")
    return out


def test_checker_finds_each_kind():
    text = ("x = 1  # see ALGORITHMS.md 3.3\n"
            "path = '../shared/DESIGN.md'\n"
            "# measured in issue 22's last stop 40\n"
            "ok = '../shared/scenes'  # the scenes' default folder is allowed\n"
            "see docs/guide/no_such_page.md and docs/guide/cli.md\n")
    found = problems("t.py", text)
    assert problems("t.md", "measured in an earlier session\n") and not problems("t.py", 'scope="session"\n')
    assert any("t.py:1: cites" in f for f in found)
    assert any("t.py:2: names a path" in f for f in found)
    assert any("t.py:3: work-item" in f for f in found)
    assert not any(f.startswith("t.py:4:") for f in found)
    assert any("no_such_page.md, which does not exist" in f for f in found)
    assert not any("docs/guide/cli.md" in f for f in found)


def test_repository_cites_only_itself():
    found = [f for p in files() for f in problems(str(p.relative_to(ROOT)), p.read_text(errors="replace"))]
    assert not found, "\n".join(found[:80]) + (f"\n... and {len(found) - 80} more" if len(found) > 80 else "")
