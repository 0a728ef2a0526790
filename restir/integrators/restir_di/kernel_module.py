"""The Warp module of ReSTIR DI's split initial, visibility and temporal kernels (`stages.split`),
compiled only when that setting asks for them; the shipped kernels stay in their stage files'
modules."""

SPLIT_MODULE = "restir_di_split"
