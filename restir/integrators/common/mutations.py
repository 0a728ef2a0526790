"""A method's fault injections for the mutation tests
(docs/validation.md#power-checks-the-mutation-table), in one registry of one
shape for every method: each name builds the method's stage kernels (in the method's own order)
with that defect, once, on first use; "none" and the mutations of the pipeline rather than of a
kernel (a race, a biased combination let through the checks) run the shipped kernels. The
harness refuses every name but "none" unless asked (restir.validation), and the shipped kernels
are built with none of them.
"""


class Mutations:
    """{name: build} with the shipped stage kernels; iterates over (and `in` tests) the names."""

    def __init__(self, shipped: tuple, builds: dict):
        """shipped: the stage kernels the method ships; builds: {name: a function returning the
        stage kernels with that defect, or None for a mutation of the pipeline}."""
        self.shipped = shipped
        self.builds = {"none": None, **builds}
        self.built: dict = {}

    def __iter__(self):
        return iter(self.builds)

    def __contains__(self, name) -> bool:
        return name in self.builds

    def __len__(self) -> int:
        return len(self.builds)

    def builds_kernels(self, name: str) -> bool:
        """Whether `name` is a fault injection built into the stage kernels (not "none", and not a
        mutation of the pipeline)."""
        return self.builds[name] is not None

    def kernels(self, name: str) -> tuple:
        """The stage kernels of the build `name`."""
        build = self.builds[name]
        if build is None:
            return self.shipped
        if name not in self.built:
            self.built[name] = build()
        return self.built[name]
