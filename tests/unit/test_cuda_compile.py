"""Every kernel module compiles for CUDA (NVRTC, no GPU needed): sm_90 (the H100/H200 the
project's device checks run on) in the fast tier, sm_86 as well in the slow tier. ReSTIR PT's and
Suffix ReSTIR's stage kernels are each one Warp module ("restir_pt", "suffix_restir"), so the code
they share (base path, shift, prefixes) compiles once per method, not once per stage file."""
import importlib
import pkgutil

import pytest
import warp as wp

from restir.kernel_modules import KERNEL_MODULES, SPLIT_MODULES, import_all


def compile_for(module, archs, tmp_path):
    wp.init()
    import_all()
    out = wp.compile_aot_module(module, arch=archs, module_dir=str(tmp_path))
    assert len(out) == len(archs) and all(p.exists() and p.stat().st_size > 0 for p in out)


# The split-stage kernels compile the same functions as the fused kernels, so their own compile
# runs in the slow tier.
@pytest.mark.parametrize("module", KERNEL_MODULES + [pytest.param(m, marks=pytest.mark.slow) for m in SPLIT_MODULES])
def test_compiles_for_cuda(module, tmp_path):
    compile_for(module, [90], tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("module", KERNEL_MODULES + SPLIT_MODULES)
def test_compiles_for_cuda_sm86(module, tmp_path):
    compile_for(module, [86], tmp_path)


def test_every_kernel_module_is_listed():
    """A new kernel module (a stage file with kernels, or a named Warp module) must be added to
    KERNEL_MODULES (restir/kernel_modules.py); fault-injected builds (made on demand) are not among the shipped ones."""
    import restir

    found = set()
    for m in pkgutil.walk_packages(restir.__path__, "restir."):
        if m.name.endswith("__main__"):
            continue
        mod = importlib.import_module(m.name)
        for v in vars(mod).values():
            if isinstance(v, wp.Kernel) and v.module.name.startswith(("restir", "suffix_restir")):
                found.add(v.module.name)
    assert found == set(KERNEL_MODULES + SPLIT_MODULES)
