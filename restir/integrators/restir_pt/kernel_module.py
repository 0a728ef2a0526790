"""The Warp modules of ReSTIR PT's shipped stage kernels: one module, so that the code they share
(the base path, the shift) is compiled once, not once per stage file (the CUDA compile check takes
minutes per module), and a second for the split trace and temporal kernels (`stages.split`),
which only that setting compiles. Fault-injected builds go to modules of their own."""

KERNEL_MODULE = "restir_pt"
SPLIT_MODULE = "restir_pt_split"
