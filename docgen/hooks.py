"""mkdocs hooks (mkdocs.yml `hooks:`): the generated reference pages join the site's files at build
time, from the code they describe (docgen/reference.py)."""
import os
import sys

from mkdocs.structure.files import File

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the repository root

from docgen.reference import PAGES  # noqa: E402


def on_files(files, config):
    for path, make in PAGES.items():
        files.append(File.generated(config, path, content=make()))
    return files
