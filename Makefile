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

# The demo: ReSTIR PT renders the indirect-lit room; then the path tracer, ReSTIR PT and Suffix ReSTIR
# at equal time, raw and through Open Image Denoise, with the error's correlation (what a denoiser
# sees) and the path tracer at each method's frame time: out/demo-compare/index.html
demo: $(STAMP)
	$(VENV)/bin/restir render builtin:indirect-room --method restir-pt --width 256 --height 256 --frames 16 \
		-o out/indirect-room.exr --png out/indirect-room.png --stats out/indirect-room.json
	$(VENV)/bin/restir compare builtin:indirect-room --method pt --method restir-pt --method suffix-restir \
		--equal-time 2.5 --width 96 --height 96 --reference-spp 1024 --denoise \
		--report out/demo-compare --json out/demo-compare.json

# The report test drives Debian's chromium with chromedriver (Selenium); nothing downloads a browser.
browser:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || { \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -q && $$SUDO apt-get install -y -q chromium chromium-driver; }

# One pytest worker per core (pytest-xdist), each test file on one worker: a worker compiles
# kernels (single-threaded) while the other runs tests; Warp's kernel cache is safe to share.
test: $(STAMP) browser
	$(VENV)/bin/pytest -q -n auto --dist loadfile

test-slow: $(STAMP) browser
	$(VENV)/bin/pytest -q -m slow

clean:
	rm -rf out .pytest_cache
