"""Shared fixtures: the device under test (--device cpu|cuda), tiny-scene helpers."""
import pytest
import warp as wp

import restir  # noqa: F401  (sets Warp's log level and codegen options first)


def pytest_addoption(parser):
    parser.addoption("--device", action="store", default="cpu", help="device the estimators run on (cpu, cuda)")


@pytest.fixture(scope="session")
def device(request):
    wp.init()
    name = request.config.getoption("--device")
    try:
        wp.get_device(name)
    except Exception:
        pytest.skip(f"device {name} not available")
    return name
