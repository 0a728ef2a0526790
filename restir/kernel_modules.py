"""The Warp modules that hold the shipped kernels: a Python module's name, or the name given to
@wp.kernel (ReSTIR PT's and Suffix ReSTIR's stage kernels are each one Warp module, so the code
they share compiles once per method). tests/unit/test_cuda_compile.py compiles them for CUDA
without a GPU and checks that the list is complete; `make gpu-bundle` compiles them ahead for
the device machine's card (gpu/bundle.py)."""
import importlib
import pkgutil

KERNEL_MODULES = [
    "restir.integrators.path",
    "restir.integrators.common.primary_hits",
    "restir.integrators.common.emission_edges",
    "restir.integrators.restir_di.s3_temporal",
    "restir.integrators.restir_di.s4_spatial",
    "restir.integrators.restir_di.s5_shade",
    "restir_pt",
    "suffix_restir",
    "restir.aov",
    "restir.film",
    "restir.integrators.common.tally",
]

# The split-stage kernels (`stages.split`, an opt-in timing layout): the same functions as the
# fused kernels above.
SPLIT_MODULES = ["restir_pt_split", "restir_di_split"]


def import_all() -> None:
    """Import every module of the package, so that every kernel is defined."""
    import restir

    for m in pkgutil.walk_packages(restir.__path__, "restir."):
        if not m.name.endswith("__main__"):
            importlib.import_module(m.name)
