"""Shared fixtures: the device under test (--device cpu|cuda), tiny-scene helpers.

Two environment switches turn on Warp's run-time checks for a whole run of the suite (the slow
tier's `make test-debug`): RESTIR_WARP_DEBUG=1 compiles every kernel in Warp's debug mode, which
bounds-checks every array access (an access out of bounds aborts the process with the kernel's
source line: on a GPU the same access would read another buffer or crash), and
RESTIR_WARP_VERIFY_FP=1 adds Warp's checks that every array element read or written and every
division's operands are finite.
"""
import os

import pytest
import warp as wp

import restir  # noqa: F401  (sets Warp's log level and codegen options first)
from tests import devices

if os.environ.get("RESTIR_WARP_DEBUG", "") == "1":
    wp.config.mode = "debug"
    # Warp 1.19 tracks a CPU launch's tile memory through one pointer per module, not per thread;
    # debug builds check it at the end of each launch, so two overlapping launches of one module
    # (the CPU slices of restir/parallel.py) read a pointer the other launch has reset and crash.
    # No kernel here uses tiles: with the tile memory out of the stack the check reads a static
    # block instead, and the slices stay concurrent.
    wp.config.enable_tiles_in_stack_memory = False
if os.environ.get("RESTIR_WARP_VERIFY_FP", "") == "1":
    wp.config.verify_fp = True


def pytest_addoption(parser):
    parser.addoption("--device", action="store", default="cpu", help="device the estimators run on (cpu, cuda)")


def pytest_configure(config):
    devices.NAME = config.getoption("--device")


@pytest.fixture(scope="session")
def device(request):
    """The device under test; the test is skipped where it does not exist (cuda on a machine
    without a GPU)."""
    wp.init()
    name = devices.NAME
    try:
        wp.get_device(name)
    except Exception:
        pytest.skip(f"device {name} not available")
    return name
