"""The tutorials (docs/tutorials/*.py, Jupyter notebooks stored as jupytext percent scripts) run
from top to bottom without a cell error, in a Jupyter kernel of this interpreter, and the links
in their Markdown cells lead to pages of the documentation site.

A tutorial states its claims as asserts in its cells (the estimate within a few standard errors
of the exact value, the biased build failing the z-test, ...), so a cell error here is either a
broken API or a claim that stopped being true. Each notebook takes well under a minute with
Warp's kernel cache warm; cold, the kernel modules it loads compile first (1-2 minutes each for
the renderer's large modules on a CPU).
"""
import json
import os
import pathlib
import re
import sys

import pytest

jupytext = pytest.importorskip("jupytext")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
from jupyter_client.kernelspec import KernelSpecManager  # noqa: E402
from jupyter_client.manager import KernelManager  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorials"
NOTEBOOKS = ["ris_and_restir_di.py", "shift_mappings.py", "conditional_ris.py"]
KERNEL = "restir-tutorials"


def kernel_manager(folder: pathlib.Path) -> KernelManager:
    """A kernel of this very interpreter (the venv's), whatever kernelspecs the machine has
    installed: its own kernelspec in a private folder."""
    spec = folder / "kernels" / KERNEL
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "restir tutorials", "language": "python"}))
    specs = KernelSpecManager(kernel_dirs=[str(folder / "kernels")])
    return KernelManager(kernel_name=KERNEL, kernel_spec_manager=specs)


def test_every_tutorial_is_in_the_site_navigation():
    """Every tutorial here is in the site's navigation (mkdocs.yml), and the other way round."""
    nav = set(re.findall(r"tutorials/([\w.]+\.py)", (ROOT / "mkdocs.yml").read_text()))
    assert nav == set(NOTEBOOKS) == {p.name for p in TUTORIALS.glob("*.py")}


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_tutorial_links_lead_to_site_pages(name):
    """mkdocs-jupyter renders a notebook's Markdown itself, so `mkdocs build --strict` does not
    check its links: a tutorial's page is served at tutorials/NAME/, and a link such as
    ../../theory/ris/#anchor must name a page of docs/ (and a heading that exists in it)."""
    nb = jupytext.read(TUTORIALS / name)
    text = "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    for link in links:
        if re.match(r"[a-z]+://", link):
            continue
        path, _, anchor = link.partition("#")
        assert path.startswith("../../") and path.endswith("/"), f"{link}: write site links as ../../PAGE/"
        page = ROOT / "docs" / (path[len("../../"):].rstrip("/") + ".md")
        assert page.exists(), f"{name}: {link} names no page of docs/"
        if anchor:
            slugs = {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-")
                     for h in re.findall(r"^#+ (.+)$", page.read_text(), re.M)}
            assert anchor in slugs, f"{name}: {link}: no heading with anchor #{anchor} in {page.name}"


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_tutorial_runs(name, tmp_path):
    nb = jupytext.read(TUTORIALS / name)
    assert any(c.cell_type == "code" for c in nb.cells)
    # started in docs/tutorials, as a reader's Jupyter would start it (the notebook finds the
    # checkout from there); MPLBACKEND unset, so that plots take the kernel's inline backend
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    client = nbclient.NotebookClient(nb, km=kernel_manager(tmp_path), timeout=600, allow_errors=False,
                                     resources={"metadata": {"path": str(TUTORIALS)}})
    client.execute(env=env)
