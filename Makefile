# Two entry points that work on a fresh machine: `make demo` and `make test`.
PY ?= python3
VENV := .venv
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow test-debug bench clean browser docs results gpu-bundle gpu-check gpu-rehearse

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

# The documentation site (MkDocs, Material): out/site/index.html. --strict: a broken link, anchor or API
# reference fails the build. The reference pages for the CLI, the settings and the scene format are
# generated from the code (docgen/). `make docs SERVE=1` serves it at http://127.0.0.1:8000 instead.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs $(if $(SERVE),serve,build --strict)

# The headline measurements (benchmarks/results_suite.py: frame cost and memory, equal time raw and
# denoised, ReSTIR DI on many lights, Mitsuba 3, scene loads, the matrix verdicts) into
# benchmarks/results/results.json, then docs/results.md and the README's status table from it.
# QUICK=1: smaller images, fewer frames and seconds.
results: $(STAMP)
	$(VENV)/bin/python benchmarks/results_suite.py $(if $(QUICK),--quick)

# The report test drives Debian's chromium with chromedriver (Selenium); nothing downloads a browser.
browser:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || { \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -q && $$SUDO apt-get install -y -q chromium chromium-driver; }

# One pytest worker per core (pytest-xdist), each test file on one worker: a worker compiles
# kernels (single-threaded) while the other runs tests; Warp's kernel cache is safe to share.
test: $(STAMP) browser
	$(VENV)/bin/pytest -q -n auto --dist loadfile

test-slow: $(STAMP) browser test-debug
	$(VENV)/bin/pytest -q -m slow

# The kernels under Warp's debug mode: every array access bounds-checked (an access out of bounds
# aborts with the kernel's source line; on a GPU it would read another buffer or crash). The unit
# tests' kernels, and every pixel stage of every method (the slicing and determinism tests, with
# settings that take the kernels' other branches); DEBUG_TESTS=tests runs the whole fast tier so.
# (Not the CUDA compile test: NVRTC's debug builds of the two largest modules take many minutes,
# and the device check loads release builds.)
DEBUG_TESTS ?= tests/unit tests/integration/test_slicing.py tests/integration/test_determinism.py \
	tests/integration/test_path_tracer.py
test-debug: $(STAMP)
	RESTIR_WARP_DEBUG=1 $(VENV)/bin/pytest -q -n auto --dist loadfile --ignore=tests/unit/test_cuda_compile.py \
		$(DEBUG_TESTS)

# The GPU check (docs/guide/gpu.md): on a device machine it runs as `python3 gpu/check.py`; here
# `make gpu-check DEVICE=cpu QUICK=1` runs the same phases at toy sizes.
DEVICE ?= cuda
gpu-check: $(STAMP)
	$(VENV)/bin/python gpu/check.py --device $(DEVICE) $(if $(QUICK),--quick) --out $(or $(GPU_OUT),out/gpu-check)

# What a bare device machine lacks (Warp, OIDN, ...), packed in parts that fit the device calls: .gpu-bundle/
gpu-bundle: $(STAMP)
	$(VENV)/bin/python gpu/bundle.py

# The bundle end to end here: the parts installed into a fresh Python 3.12 with the device's
# packages, imported, and the check run from it on the CPU at toy sizes.
gpu-rehearse: gpu-bundle
	bash gpu/rehearse.sh

clean:
	rm -rf out .pytest_cache
