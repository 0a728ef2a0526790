"""ReSTIR DI (Bitterli et al. 2020) on the shared resampling core. See docs/guide/restir_di.md."""
