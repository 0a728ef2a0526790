"""The documentation site: `mkdocs build --strict` (what `make docs` runs) succeeds, so no page
has a broken link, anchor or API reference; the same build fails on a broken link (the strict
check has power); and the built site works in a real browser (Debian's chromium through
Selenium): every page in the navigation opens, every image on it decodes, and the search finds
pages."""
import functools
import http.server
import os
import pathlib
import shutil
import subprocess
import sys
import threading

import pytest

from tests.browser import chromium

ROOT = pathlib.Path(__file__).resolve().parents[2]
# the tutorials are run by tests/integration/test_tutorials.py; here they are rendered without running
ENV = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "RESTIR_DOCS_EXECUTE": "false"}


def mkdocs_build(config: pathlib.Path, site: pathlib.Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
                          capture_output=True, text=True, env=ENV, timeout=600, cwd=config.parent)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site") / "site"
    p = mkdocs_build(ROOT / "mkdocs.yml", out)
    assert p.returncode == 0, p.stdout[-4000:] + p.stderr[-4000:]
    return out


def test_strict_build_fails_on_a_broken_link(tmp_path):
    copy = tmp_path / "repo"
    copy.mkdir()
    shutil.copy(ROOT / "mkdocs.yml", copy / "mkdocs.yml")
    shutil.copytree(ROOT / "docs", copy / "docs")
    shutil.copytree(ROOT / "docgen", copy / "docgen", ignore=shutil.ignore_patterns("__pycache__"))
    with open(copy / "docs" / "getting_started.md", "a") as f:
        f.write("\nSee [a page that is not there](guide/no_such_page.md).\n")
    p = mkdocs_build(copy / "mkdocs.yml", tmp_path / "site")
    assert p.returncode != 0 and "no_such_page.md" in p.stdout + p.stderr


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):  # one line per request would bury pytest's output
        pass


@pytest.fixture(scope="module")
def server(site):
    handler = functools.partial(QuietHandler, directory=str(site))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/"
    httpd.shutdown()


def test_site_in_a_browser(site, server):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import WebDriverWait

    # nothing outside this machine: MathJax's CDN fails at once instead of holding every page's load
    driver = chromium(extra_args=("--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1",))
    try:
        driver.get(server)
        assert "restir" in driver.title
        links = driver.execute_script(
            "return [...document.querySelectorAll('nav.md-nav--primary a.md-nav__link[href]')].map(a => a.href)")
        pages = sorted({u.split("#")[0] for u in links if u.startswith(server)})
        # every page of mkdocs.yml's nav (sections are labels, not links)
        assert len(pages) >= 30, pages
        broken_images, not_found = [], []
        for url in pages:
            driver.get(url)
            WebDriverWait(driver, 20).until(lambda d: d.execute_script("return document.readyState") == "complete")
            if "404" in driver.title or not driver.find_elements(By.CSS_SELECTOR, "article.md-content__inner h1"):
                not_found.append(url)
            WebDriverWait(driver, 20).until(lambda d: d.execute_script(
                "return [...document.images].every(i => i.complete)"))
            broken_images += [f"{url}: {src}" for src in driver.execute_script(
                "return [...document.images].filter(i => i.naturalWidth === 0).map(i => i.src)")]
        assert not not_found, not_found
        assert not broken_images, broken_images

        driver.get(server)
        box = WebDriverWait(driver, 20).until(lambda d: d.find_element(By.CSS_SELECTOR, "input.md-search__input"))
        box.click()
        box.send_keys("reservoir")
        results = WebDriverWait(driver, 30).until(lambda d: d.find_elements(By.CSS_SELECTOR, ".md-search-result__item"))
        hrefs = [r.find_element(By.TAG_NAME, "a").get_attribute("href") for r in results]
        assert any("theory/" in h for h in hrefs), hrefs
        box.send_keys(Keys.ENTER)
        WebDriverWait(driver, 20).until(lambda d: d.current_url != server)
        assert driver.current_url.startswith(server)
    finally:
        driver.quit()
