"""The developer guide (docs/developer/architecture.md, docs/developer/new_method.md) names the
code's files, functions, classes and settings; this test checks that each one it names exists
where the page says, so that the guide cannot drift from the code unnoticed. The code is read
with `ast` (nothing of restir is imported, no kernel is compiled).

What a page is checked for (fenced code blocks are skipped, but for the file trees of rule 4):

1. Repository paths, anywhere in the text: a token that starts with `restir/`, `tests/`,
   `benchmarks/`, `docgen/` or `gpu/`, a file or (ending in `/`) a folder, must exist. `*` is a
   glob (it must match something); `{a,b}` lists alternatives (each must exist); a path with an
   upper-case placeholder part (`restir/integrators/NAME/`) is a template and is not checked. A
   `.py` path that starts anywhere else (`path_reuse/shift.py`) is refused: write it from the
   repository root. A bare file name in backticks (`pipeline.py`) must be the name of a file
   under restir/.
2. Names, in inline code (single backticks):
   - every call in the span, `name(` or `a.b.name(`;
   - a span that is one identifier or dotted name as a whole, when it looks like code: it has
     an underscore, or is CamelCase, or is UPPER_CASE of four letters or more, or is dotted.
   Lower-case words without an underscore that are not called (`pt`, `none`) are not names,
   nor are spans with spaces, `=` or `-` outside a call (`restir info`, `direct=pt`).
   A dotted span that is a method setting's key (`debug.mutation`, `di.spatial.rounds`; `rc.*`
   for a group) is checked as one: it must be the key of a `setting(...)` in restir/, under at
   most two component prefixes (`component(...)`, `spatial_reuse(...)`). A span whose first
   part is `wp`, `np` or another outside module is skipped.
3. Where a name must be ("where the page says"): its scope is the table row, list item or
   paragraph it is in; the scope's files are the repository paths the scope mentions (a folder
   stands for every .py file under it).
   - unqualified `name`: defined in one of the scope's files (in any indexed file when the scope
     mentions none). Defined: a def or class at any depth (a kernel built inside a factory
     counts), a module- or class-level assignment or annotated field, an attribute a method
     sets on `self`; in a package's __init__.py also what it imports (its public names). A
     lower-case name also passes when it is a module's name (`kernel_module`), and a snake_case
     one when it is a string literal of any indexed file (a value, not a definition: a stage's
     name in STAGES, a debug.mutation name, a stats key). Dunder names are Python's.
   - `Class.attr` (Class: a class of the indexed files): attr is defined in the class, set on
     `self` by one of its methods, or found in a base class (by name).
   - `module.name` (module: a file's stem, or a dotted path `restir.x.y`): name is defined at
     the top level of that module (of the modules with that stem, those in the scope first); a
     dotted path that is itself a module (`restir.validation`) passes.
   - `self.attr...`: attr is an attribute or method of a class in the scope's files (anywhere
     when none).
   - `var.attr` (var: a module-level variable such as `MUTATIONS`): var is defined in the scope's
     files; what follows is not checked.
4. File trees: a fenced block whose first line is a repository folder ending in `/`. Each
   further line whose first word ends in `.py` or `/` names a file or folder, two spaces of
   indent per level below the folder above it (a line at indent 0 that ends in `/` starts a
   new tree). Each must exist, and a folder the tree opens (lists anything in) must be listed
   completely: every .py file but `__init__.py`, and every subfolder holding .py files.

Indexed files: every .py file under restir/, tests/, benchmarks/, docgen/ and gpu/.
"""
import ast
import functools
import glob
import os
import re
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PAGES = ("docs/developer/architecture.md", "docs/developer/new_method.md")
PATH_ROOTS = ("restir", "tests", "benchmarks", "docgen", "gpu")
EXTERNAL = {"wp", "warp", "np", "numpy", "dataclasses", "functools", "pytest", "argparse", "os", "sys", "ray",
            "mkdocs", "pkgutil", "importlib", "threading", "json"}

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
DOTTED = re.compile(rf"^{IDENT}(\.{IDENT})*$")
CALL = re.compile(rf"(?<![\w.])({IDENT}(?:\.{IDENT})*)\(")
REPO_PATH = re.compile(rf"(?<![\w./-])(?:{'|'.join(PATH_ROOTS)})/[\w./*{{}},-]*")
OTHER_PY_PATH = re.compile(r"(?<![\w./-])([\w-]+/)+[\w*]+\.py\b")
SPAN = re.compile(r"(?<!`)`([^`\n]+)`(?!`)")


# ----------------------------------------------------------------------------- the code's index
class FileIndex:
    """What one source file defines (see the module docstring, rule 3)."""

    def __init__(self, path: str):
        self.path = path
        tree = ast.parse(open(path, encoding="utf-8").read())
        self.top: set = set()      # module-level names
        self.all: set = set()      # every name defined at any depth, class members and self attributes
        self.strings: set = set()  # string literals
        self.classes: dict = {}    # name -> (members, base names)
        is_init = path.endswith("__init__.py")
        for node in tree.body:
            self.top.update(_bound_names(node, imports=is_init))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                self.all.add(node.name)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                self.strings.add(node.value)
            if isinstance(node, ast.ClassDef):
                members = set()
                for stmt in node.body:
                    members.update(_bound_names(stmt, imports=False))
                for sub in ast.walk(node):
                    if isinstance(sub, ast.Attribute) and isinstance(sub.ctx, ast.Store) and \
                            isinstance(sub.value, ast.Name) and sub.value.id == "self":
                        members.add(sub.attr)
                bases = [b.id if isinstance(b, ast.Name) else b.attr for b in node.bases
                         if isinstance(b, (ast.Name, ast.Attribute))]
                self.classes[node.name] = (members, bases)
                self.all.update(members)
        self.all.update(self.top)


def _bound_names(node, imports: bool) -> set:
    """Names a module- or class-level statement binds (into if/try blocks, not into functions)."""
    out = set()
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        out.add(node.name)
    elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        for t in targets:
            for n in ast.walk(t):
                if isinstance(n, ast.Name):
                    out.add(n.id)
    elif isinstance(node, (ast.Import, ast.ImportFrom)) and imports:
        out.update((a.asname or a.name).split(".")[0] for a in node.names)
    elif isinstance(node, (ast.If, ast.Try, ast.With, ast.For)):
        for part in ("body", "orelse", "finalbody", "handlers"):
            for sub in getattr(node, part, []):
                for s in (sub.body if isinstance(sub, ast.ExceptHandler) else [sub]):
                    out.update(_bound_names(s, imports))
    return out


class CodeIndex:
    def __init__(self, root: str):
        self.root = root
        self.files: dict = {}  # repository path -> FileIndex
        for top in PATH_ROOTS:
            for d, dirs, files in os.walk(os.path.join(root, top)):
                dirs[:] = [x for x in dirs if x != "__pycache__"]
                for f in files:
                    if f.endswith(".py"):
                        full = os.path.join(d, f)
                        self.files[os.path.relpath(full, root).replace(os.sep, "/")] = FileIndex(full)
        self.stems: dict = {}    # file stem (package name for __init__) -> [repository paths]
        self.dotted: dict = {}   # restir.x.y -> repository path
        self.classes: dict = {}  # class name -> [(members, bases)]
        for rel, fi in self.files.items():
            parts = rel[:-3].split("/")
            if parts[-1] == "__init__":
                parts = parts[:-1]
            self.stems.setdefault(parts[-1], []).append(rel)
            self.dotted[".".join(parts)] = rel
            for name, cls in fi.classes.items():
                self.classes.setdefault(name, []).append(cls)
        self.file_names = {rel.rsplit("/", 1)[-1] for rel in self.files if rel.startswith("restir/")}
        self.setting_keys, self.setting_prefixes = self._settings()

    def _settings(self) -> tuple:
        keys, prefixes = set(), set()
        for rel in self.files:
            if not rel.startswith("restir/"):
                continue
            for node in ast.walk(ast.parse(open(os.path.join(self.root, rel), encoding="utf-8").read())):
                if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.args and \
                        isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                    if node.func.id == "setting":
                        keys.add(node.args[0].value)
                    elif node.func.id in ("component", "spatial_reuse"):
                        prefixes.add(node.args[0].value)
        return keys, prefixes

    def is_setting_key(self, text: str) -> bool:
        full = set(self.setting_keys)
        full |= {p + k for p in self.setting_prefixes for k in full}
        full |= {p + k for p in self.setting_prefixes for k in full}
        if text.endswith(".*"):
            return any(k.startswith(text[:-1]) for k in full)
        return text in full

    def files_under(self, path: str) -> list:
        """The indexed files a repository path stands for (a folder: every file under it)."""
        path = path.rstrip("/")
        return [rel for rel in self.files if rel == path or rel.startswith(path + "/")]

    def class_has(self, name: str, attr: str, seen=()) -> bool:
        for members, bases in self.classes.get(name, []):
            if attr in members:
                return True
            if any(self.class_has(b, attr, seen + (name,)) for b in bases if b not in seen):
                return True
        return False


@functools.cache
def code_index(root: str = ROOT) -> CodeIndex:
    return CodeIndex(root)


# ----------------------------------------------------------------------------- the page's parts
def split_page(text: str) -> tuple[list, list]:
    """(scopes: lists of lines outside fenced blocks, split at blank lines, list items, table rows
    and headings; fenced blocks: (info string, lines))."""
    scopes, fences, current = [], [], []
    fence = None

    def close():
        if current:
            scopes.append(list(current))
            current.clear()

    for line in text.splitlines():
        stripped = line.strip()
        if fence is not None:
            if stripped.startswith("```"):
                fences.append(fence)
                fence = None
            else:
                fence[1].append(line)
            continue
        if stripped.startswith("```"):
            close()
            fence = (stripped[3:].strip(), [])
            continue
        if not stripped:
            close()
        elif stripped.startswith("|") or stripped.startswith("#"):
            close()
            scopes.append([line])
        elif re.match(r"^\s*([-*+]|\d+\.)\s", line):
            close()
            current.append(line)
        else:
            current.append(line)
    close()
    return scopes, fences


def expand_path(path: str) -> list:
    m = re.search(r"\{([^{}]*)\}", path)
    if not m:
        return [path]
    return [p for alt in m.group(1).split(",") for p in expand_path(path[:m.start()] + alt + path[m.end():])]


def check_paths(text: str, index: CodeIndex, where: str) -> list:
    problems = []
    for m in REPO_PATH.finditer(text):
        token = m.group(0).rstrip(".,;:)")
        if "{" in token and "}" not in token:  # a brace set cut by the token's end
            continue
        for path in expand_path(token):
            if any(re.fullmatch(r"[A-Z][A-Z_]+", part) for part in path.split("/")):
                continue  # a template: restir/integrators/NAME/
            full = os.path.join(index.root, path)
            exists = bool(glob.glob(full)) if "*" in path else os.path.exists(full)
            if path.endswith("/") and exists and "*" not in path:
                exists = os.path.isdir(full)
            if not exists:
                problems.append(f"{where}: the path {path} does not exist")
    for m in OTHER_PY_PATH.finditer(text):
        if not m.group(0).startswith(tuple(r + "/" for r in PATH_ROOTS)):
            start = m.start()
            if start > 0 and text[start - 1] in "./":
                continue
            problems.append(f"{where}: the path {m.group(0)} does not start at the repository root")
    return problems


def span_names(span: str) -> list:
    """The names a code span holds (rule 2)."""
    s = span.strip()
    if s.startswith("@"):
        s = s[1:]
    names = [m.group(1) for m in CALL.finditer(s)]
    if DOTTED.match(s) and s not in names:
        if "." in s or "_" in s or re.fullmatch(r"[A-Z][A-Za-z0-9]*[a-z][A-Za-z0-9]*", s) or \
                re.fullmatch(r"[A-Z][A-Z0-9]{3,}", s):
            names.append(s)
    return names


def resolve(name: str, scope_files: list, index: CodeIndex) -> str | None:
    """None when `name` exists where the scope says; else what is missing (rule 3)."""
    parts = name.split(".")
    first = parts[0]
    if first in EXTERNAL:
        return None
    if len(parts) > 1 and index.is_setting_key(name):
        return None
    files = scope_files or list(index.files)
    if first == "self":
        if len(parts) == 1:
            return None
        attr = parts[1]
        classes = [c for rel in files for c in index.files[rel].classes]
        if any(index.class_has(c, attr) for c in classes):
            return None
        return f"no class of {_where(scope_files)} has the attribute {attr}"
    if name in index.dotted:
        return None  # a module: restir.validation
    if len(parts) == 1:
        if name.startswith("__") and name.endswith("__"):
            return None  # __init__, __main__: Python's names
        if any(name in index.files[rel].all for rel in files):
            return None
        if name in index.stems and name == name.lower():
            return None  # a module's name: kernel_module
        if "_" in name and name == name.lower() and any(name in fi.strings for fi in index.files.values()):
            return None  # a value: a stage's name, a mutation's, a stats key
        return f"{name} is not defined in {_where(scope_files)}"
    if first in index.classes:
        if index.class_has(first, parts[1]):
            return None
        return f"the class {first} has no attribute {parts[1]}"
    for n in range(len(parts) - 1, 0, -1):  # the longest prefix that is a module: restir.x.y or a stem
        head = ".".join(parts[:n])
        if head in index.dotted:
            modules = [index.dotted[head]]
        elif n == 1 and head in index.stems:
            modules = index.stems[head]
            modules = [m for m in modules if m in scope_files] or modules
        else:
            continue
        if any(parts[n] in index.files[m].top for m in modules):
            return None
        return f"the module {head} ({', '.join(modules)}) defines no {parts[n]}"
    if any(first in index.files[rel].top for rel in files):
        return None  # a module-level variable (MUTATIONS.kernels): the rest is not checked
    if name == name.lower() and re.fullmatch(r"[a-z0-9_.]+", name):
        return f"{name} is neither a setting's key nor a name of {_where(scope_files)}"
    return f"{first} is not defined in {_where(scope_files)}"


def _where(scope_files: list) -> str:
    return ", ".join(scope_files) if scope_files else "any indexed file"


def check_scope(lines: list, index: CodeIndex, where: str) -> list:
    text = "\n".join(lines)
    problems = check_paths(text, index, where)
    scope_files = []
    for m in REPO_PATH.finditer(text):
        for path in expand_path(m.group(0).rstrip(".,;:)")):
            if "*" in path:
                scope_files += [rel for g in glob.glob(os.path.join(index.root, path))
                                for rel in index.files_under(os.path.relpath(g, index.root).replace(os.sep, "/"))]
            else:
                scope_files += index.files_under(path)
    scope_files = list(dict.fromkeys(scope_files))
    for m in SPAN.finditer(text):
        span = m.group(1)
        s = span.strip()
        if re.fullmatch(r"[\w.*-]+\.py", s) and "/" not in s:
            if s not in index.file_names and "*" not in s:
                problems.append(f"{where}: no file under restir/ is named {s}")
            continue
        for name in span_names(span):
            problem = resolve(name, scope_files, index)
            if problem:
                problems.append(f"{where}: `{span}`: {problem}")
    return problems


def check_tree(lines: list, index: CodeIndex, where: str) -> list:
    problems, stack, opened = [], [], {}
    for line in lines:
        if not line.strip():
            continue
        indent = len(line) - len(line.lstrip(" "))
        word = line.split()[0]
        if indent == 0 and word.endswith("/"):
            stack = [word]
            opened.setdefault(word, set())
            continue
        if not (word.endswith(".py") or word.endswith("/")) or not stack:
            continue
        level = indent // 2
        stack = stack[:level]
        if not stack:
            problems.append(f"{where}: {word} is indented under no folder")
            continue
        parent = "".join(stack)
        path = parent + word
        opened.setdefault(parent, set()).add(word)
        if not os.path.exists(os.path.join(index.root, path)):
            problems.append(f"{where}: the tree lists {path}, which does not exist")
        if word.endswith("/"):
            stack.append(word)
    for folder, listed in opened.items():
        if not listed:
            continue
        full = os.path.join(index.root, folder)
        if not os.path.isdir(full):
            continue
        actual = set()
        for entry in os.listdir(full):
            p = os.path.join(full, entry)
            if entry.endswith(".py") and entry != "__init__.py":
                actual.add(entry)
            elif os.path.isdir(p) and entry != "__pycache__" and \
                    glob.glob(os.path.join(p, "**", "*.py"), recursive=True):
                actual.add(entry + "/")
        for missing in sorted(actual - listed):
            problems.append(f"{where}: the tree opens {folder} but does not list {missing}")
    return problems


def check_page(text: str, index: CodeIndex | None = None, name: str = "page") -> list:
    """Every problem of the page, as 'name: scope: what'."""
    index = index or code_index()
    scopes, fences = split_page(text)
    problems = []
    for lines in scopes:
        problems += check_scope(lines, index, f"{name}: {lines[0].strip()[:60]!r}")
    for _, lines in fences:
        first = next((ln for ln in lines if ln.strip()), "")
        if first and not first.startswith(" ") and first.split()[0].endswith("/") and \
                first.split()[0].startswith(tuple(r + "/" for r in PATH_ROOTS)):
            if any(re.fullmatch(r"[A-Z][A-Z_]+", p) for p in first.split()[0].split("/")):
                continue  # a template's tree
            problems += check_tree(lines, index, f"{name}: the tree {first.split()[0]}")
    return problems


# ----------------------------------------------------------------------------- the tests
def _page(path: str) -> str:
    return open(os.path.join(ROOT, path), encoding="utf-8").read()


def test_architecture_names_what_exists():
    assert check_page(_page(PAGES[0]), name=PAGES[0]) == []


def test_new_method_names_what_exists():
    assert check_page(_page(PAGES[1]), name=PAGES[1]) == []


def test_the_pages_name_code():
    """The extraction finds what the pages are about (an empty extraction would pass anything)."""
    for page in PAGES:
        scopes, fences = split_page(_page(page))
        names = [n for lines in scopes for m in SPAN.finditer("\n".join(lines)) for n in span_names(m.group(1))]
        paths = [m.group(0) for lines in scopes for m in REPO_PATH.finditer("\n".join(lines))]
        assert len(names) >= 40 and len(paths) >= 20, (page, len(names), len(paths))


def test_the_checker_reports_what_is_missing():
    text = "\n".join([
        "| need | call | file |",
        "|---|---|---|",
        "| a render | `render(scene)`, `no_such_function(x)` | `restir/api.py` |",
        "| nothing | `helper` | `restir/integrators/no_such_module.py` |",
        "",
        "`Integrator.no_such_method`, `api.no_such_thing`, `debug.no_such_key` and `Integrator.render_frame`",
        "are named here; `restir/integrators/base.py` is real, `integrators/base.py` is no repository path.",
        "",
        "```",
        "restir/integrators/",
        "  base.py       the base",
        "  common/",
        "    gbuffer.py",
        "    no_such_file.py",
        "```",
    ])
    problems = check_page(text)
    joined = "\n".join(problems)
    assert "restir/integrators/no_such_module.py does not exist" in joined
    assert "no_such_function is not defined in restir/api.py" in joined
    assert "the class Integrator has no attribute no_such_method" in joined
    assert "the module api (restir/api.py) defines no no_such_thing" in joined
    assert "debug.no_such_key is neither a setting's key" in joined
    assert "integrators/base.py does not start at the repository root" in joined
    assert "restir/integrators/common/no_such_file.py, which does not exist" in joined
    assert "does not list path.py" in joined            # the tree opens restir/integrators/ ...
    assert "does not list shading.py" in joined         # ... and common/ without all their files
    assert "`render(scene)`:" not in joined and "`Integrator.render_frame`:" not in joined  # what exists passes
    assert len(problems) >= 9


def test_the_checker_resolves_names_where_the_page_says():
    """A name that exists elsewhere but not in the files its row names is reported."""
    text = "| a shading point | `load_shading(scene, gb, pixel)` | `restir/device/bounce.py` |"
    assert any("load_shading is not defined in restir/device/bounce.py" in p for p in check_page(text))
    text = "| a shading point | `load_shading(scene, gb, pixel)` | `restir/integrators/common/shading.py` |"
    assert check_page(text) == []


def test_the_check_is_fast():
    code_index.cache_clear()
    t0 = time.perf_counter()
    for page in PAGES:
        check_page(_page(page), name=page)
    assert time.perf_counter() - t0 < 5.0
