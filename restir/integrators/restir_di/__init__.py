"""ReSTIR DI (Bitterli et al. 2020) on the shared resampling core. See docs/restir_di.md."""
