"""docs/results.md and the README's status table are generated from benchmarks/results/results.json
(docgen/results.py): the committed files must be what the committed JSON gives, and a number
changed in the JSON must show in both. No rendering: the generator reads the JSON only."""
import copy
import json
import pathlib

import pytest

from docgen.results import BEGIN, END, render_results_page, render_status_table, update_readme

ROOT = pathlib.Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results" / "results.json"
REGENERATE = "regenerate with `.venv/bin/python -m docgen.results` (or `make results` to measure again)"


@pytest.fixture(scope="module")
def results():
    return json.loads(RESULTS.read_text())


def test_results_page_is_generated_from_the_results(results):
    page = (ROOT / "docs" / "results.md").read_text()
    assert page == render_results_page(results), f"docs/results.md differs from benchmarks/results/results.json: " \
                                                 f"{REGENERATE}"


def test_readme_status_table_is_generated_from_the_results(results):
    readme = (ROOT / "README.md").read_text()
    assert BEGIN in readme and END in readme, "README.md lost its status-table markers"
    assert readme == update_readme(readme, render_status_table(results)), \
        f"README.md's status table differs from benchmarks/results/results.json: {REGENERATE}"


def test_a_changed_number_changes_the_page_and_the_table(results):
    changed = copy.deepcopy(results)
    cost = changed["cost"]["methods"]["restir-pt"]
    cost["ratio_median"] = 123.456
    scene = next(s for s in changed["equal_time"]["scenes"] if "methods" in s)
    head = next(m for m in scene["methods"] if m["label"] == "restir-pt")["against_pt"]
    head["denoised_frame"] = 0.5 if head["denoised_frame"] > 1 else 2.5
    page, table = render_results_page(changed), render_status_table(changed)
    assert page != render_results_page(results) and table != render_status_table(results)
    assert "123.46x" in page and "123.46x" in table
    assert ("no (0.50x)" if head["denoised_frame"] < 1 else "pays (2.50x)") in table


def test_update_readme_replaces_only_the_block():
    text = f"# title\n\nbefore\n{BEGIN}\nold table\nold line\n{END}\nafter\n"
    new = update_readme(text, "| a |\n|---|")
    assert new == f"# title\n\nbefore\n{BEGIN}\n| a |\n|---|\n{END}\nafter\n"
    assert update_readme(new, "| a |\n|---|") == new
    assert update_readme("no markers here\n", "| a |") == "no markers here\n"
    assert update_readme(f"{END}\n{BEGIN}\n", "| a |") == f"{END}\n{BEGIN}\n"  # out of order: untouched
