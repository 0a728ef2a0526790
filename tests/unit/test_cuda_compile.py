"""Every kernel module compiles for CUDA (NVRTC, no GPU needed): sm_90 (the H100/H200 the
project's device checks run on) in the fast tier, sm_86 as well in the slow tier (ReSTIR PT's
stages, with the shift inlined several times, take about 45 s per architecture each)."""
import importlib

import pytest
import warp as wp

KERNEL_MODULES = [
    "restir.integrators.path",
    "restir.integrators.common.primary_hits",
    "restir.integrators.restir_di.s2_initial",
    "restir.integrators.restir_di.s3_visibility",
    "restir.integrators.restir_di.s4_temporal",
    "restir.integrators.restir_di.s5_spatial",
    "restir.integrators.restir_di.s6_shade",
    "restir.integrators.restir_pt.s1_initial",
    "restir.integrators.restir_pt.s2_temporal",
    "restir.integrators.restir_pt.s3_spatial",
    "restir.integrators.restir_pt.s4_shade",
    "restir.integrators.suffix_restir.s1_prefix",
    "restir.integrators.suffix_restir.search",
    "restir.integrators.suffix_restir.s3_suffix",
    "restir.integrators.suffix_restir.s4_suffix_temporal",
    "restir.integrators.suffix_restir.s5_suffix_spatial",
    "restir.integrators.suffix_restir.s6_gather",
]


def compile_for(module, archs, tmp_path):
    wp.init()
    out = wp.compile_aot_module(importlib.import_module(module), arch=archs, module_dir=str(tmp_path))
    assert len(out) == len(archs) and all(p.exists() and p.stat().st_size > 0 for p in out)


@pytest.mark.parametrize("module", KERNEL_MODULES)
def test_compiles_for_cuda(module, tmp_path):
    compile_for(module, [90], tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("module", KERNEL_MODULES)
def test_compiles_for_cuda_sm86(module, tmp_path):
    compile_for(module, [86], tmp_path)


def test_every_kernel_module_is_listed():
    """A new stage file with kernels must be added to KERNEL_MODULES above."""
    import pkgutil

    import restir

    found = set()
    for m in pkgutil.walk_packages(restir.__path__, "restir."):
        if m.name.endswith("__main__"):
            continue
        mod = importlib.import_module(m.name)
        if any(isinstance(v, wp.Kernel) and v.module.name == m.name for v in vars(mod).values()):
            found.add(m.name)
    assert found == set(KERNEL_MODULES)
