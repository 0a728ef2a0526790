"""The package outside the editable checkout: a wheel built from the tree installs into a fresh
virtual environment, and the `restir` command there renders the Cornell box from the installed
files (not the checkout's).

The fresh environment gets restir's dependencies from the test's own environment through a path
entry (a `.pth` line naming its site-packages): a path entry adds the folder to sys.path without
running the `.pth` files inside it, so the checkout's editable install stays out and `import
restir` can only find the wheel's copy. No network is needed: the wheel is built without build
isolation (setuptools and build are test dependencies)."""
import importlib.util
import os
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import venv

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
SKIP = shutil.ignore_patterns(".git", ".venv", "out", "build", "dist", "*.egg-info", "__pycache__", ".gpu-bundle",
                              ".pytest_cache", ".hypothesis")


def test_license_is_an_spdx_string():
    # setuptools refuses the TOML-table form from 2027-02-18 on, and warns about it on every install until then
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert isinstance(project["license"], str) and project["license"] == "MIT"


def test_wheel_installs_and_renders(tmp_path):
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=SKIP)
    dist = tmp_path / "dist"
    build = subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation", "--outdir", str(dist),
                            str(src)], capture_output=True, text=True, timeout=300)
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    assert "License classifiers are deprecated" not in build.stderr and "project.license" not in build.stderr
    wheels = list(dist.glob("restir-*.whl"))
    assert len(wheels) == 1

    env_dir = tmp_path / "fresh"
    venv.EnvBuilder(with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    (pathlib.Path(site) / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    # pip from the test's environment installs the wheel alone into the fresh one's site-packages
    # (--target with --ignore-installed: with --prefix, pip would first uninstall the test
    # environment's own restir)
    inst = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "--ignore-installed",
                           "--target", site, str(wheels[0])], capture_output=True, text=True, timeout=300)
    assert inst.returncode == 0, inst.stdout[-2000:] + inst.stderr[-2000:]

    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    where = subprocess.run([str(py), "-c", "import restir, restir_cli; print(restir.__file__)"], cwd=work, env=env,
                           capture_output=True, text=True, timeout=120)
    assert where.returncode == 0, where.stderr[-2000:]
    assert pathlib.Path(where.stdout.strip()).is_relative_to(env_dir), where.stdout
    assert importlib.util.find_spec("restir").origin.startswith(str(ROOT))  # the checkout's install untouched

    out = work / "cb.npy"
    # the installed console script, run by the fresh interpreter (pip wrote the test environment's
    # interpreter into its first line)
    run = subprocess.run([str(py), str(pathlib.Path(site) / "bin" / "restir"), "render", "builtin:cornell-box",
                          "--spp", "4", "--width", "32", "--height", "32", "-o", str(out), "--quiet"],
                         cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    image = np.load(out)
    assert image.shape == (32, 32, 3) and np.isfinite(image).all()
    assert 0.05 < float(image.mean()) < 5.0  # a lit box, not a black or blown-out image
