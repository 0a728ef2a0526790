# Two entry points that work on a fresh machine: `make demo` and `make test`.
PY ?= python3
VENV := .venv
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow bench clean browser

$(STAMP): pyproject.toml
	test -d $(VENV) || $(PY) -m venv $(VENV)
	$(VENV)/bin/pip install -q --upgrade pip
	$(VENV)/bin/pip install -q -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/restir render builtin:cornell-box --width 512 --height 512 --spp 16 \
		-o out/cornell-box.exr --png out/cornell-box.png --stats out/cornell-box.json
	$(VENV)/bin/restir compare builtin:cornell-box --method pt --method restir-di --equal-time 4 \
		--width 128 --height 128 --reference-spp 256 --report out/demo-compare

# The report test drives Debian's chromium with chromedriver (Selenium); nothing downloads a browser.
browser:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || { \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -q && $$SUDO apt-get install -y -q chromium chromium-driver; }

test: $(STAMP) browser
	$(VENV)/bin/pytest -q

test-slow: $(STAMP) browser
	$(VENV)/bin/pytest -q -m slow

clean:
	rm -rf out .pytest_cache
