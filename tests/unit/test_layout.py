"""The package layout docs/developer/new_method.md promises, checked on the source: no import circle
between restir's modules (imports inside functions count: they only hide a circle), and no
method importing another method's package (methods share `common/` and `path_reuse/`)."""
import ast
import os

import restir

ROOT = os.path.dirname(restir.__file__)
METHODS = ("restir_di", "restir_pt", "suffix_restir")


def module_name(path: str) -> str:
    rel = os.path.relpath(path, os.path.dirname(ROOT))[:-3].replace(os.sep, ".")
    return rel[:-len(".__init__")] if rel.endswith(".__init__") else rel


def modules() -> dict:
    out = {}
    for d, _, files in os.walk(ROOT):
        for f in files:
            if f.endswith(".py"):
                out[module_name(os.path.join(d, f))] = os.path.join(d, f)
    return out


def imports(name: str, path: str, known: set) -> set:
    """The restir modules `name` imports (a `from pkg import sub` of a submodule counts as sub)."""
    package = name if path.endswith("__init__.py") else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(open(path).read())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "restir")
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parent = ".".join(parts[:len(parts) - node.level + 1])
                base = f"{parent}.{base}" if base else parent
            if base.split(".")[0] != "restir":
                continue
            for a in node.names:
                sub = f"{base}.{a.name}"
                out.add(sub if sub in known else base)
    return out - {name}


def graph() -> dict:
    mods = modules()
    return {m: {d for d in imports(m, p, set(mods)) if d in mods} for m, p in mods.items()}


def test_no_import_circle():
    g = graph()
    # Package __init__ files only re-export their contents; a module importing its own package's
    # __init__ is not a circle of content.
    g = {m: {d for d in deps if not m.startswith(d + ".")} for m, deps in g.items()}
    state, stack, circles = {}, [], []

    def visit(m):
        state[m] = "open"
        stack.append(m)
        for d in sorted(g[m]):
            if state.get(d) == "open":
                circles.append(stack[stack.index(d):] + [d])
            elif d not in state:
                visit(d)
        stack.pop()
        state[m] = "done"

    for m in sorted(g):
        if m not in state:
            visit(m)
    assert not circles, "import circles: " + "; ".join(" -> ".join(c) for c in circles)


def test_methods_do_not_import_each_other():
    g = graph()
    bad = []
    for m, deps in g.items():
        own = next((k for k in METHODS if f".integrators.{k}" in m), None)
        if own is None:
            continue
        bad += [(m, d) for d in deps for k in METHODS if k != own and f".integrators.{k}" in d]
    assert not bad, bad


def test_stage_files_numbered_from_s1_in_order():
    """One numbering convention (docs/developer/new_method.md): a method's own stage files are s1_*.py,
    s2_*.py, ... without gaps or repeats (numbered in the order the pipeline runs them; the shared
    primary hits and the direct-light component are not numbered), and the pipeline imports each."""
    import re

    for method in METHODS:
        folder = os.path.join(ROOT, "integrators", method)
        stages = sorted((int(m.group(1)), f) for f in os.listdir(folder) if (m := re.match(r"s(\d+)_\w+\.py$", f)))
        assert [n for n, _ in stages] == list(range(1, len(stages) + 1)), (method, stages)
        pipeline = open(os.path.join(folder, "pipeline.py")).read()
        for _, f in stages:
            assert f"from .{f[:-3]} import" in pipeline, (method, f)


def test_test_files_share_helpers_not_each_other():
    """Test files share code through the helper modules (tests/helpers.py, tests/scenes.py,
    tests/shared_scenes.py, tests/unit/shift_harness.py, tests/data/), never by importing another
    test file."""
    tests = os.path.join(os.path.dirname(ROOT), "tests")
    bad = []
    for d, _, files in os.walk(tests):
        for f in files:
            if f.startswith("test_") and f.endswith(".py"):
                for node in ast.walk(ast.parse(open(os.path.join(d, f)).read())):
                    names = [node.module or ""] if isinstance(node, ast.ImportFrom) else \
                        [a.name for a in node.names] if isinstance(node, ast.Import) else []
                    bad += [(f, n) for n in names if n.startswith("tests.") and n.rpartition(".")[2].startswith("test_")]
    assert not bad, bad
