"""Device library: @wp.func and @wp.struct building blocks, no kernel launches, no I/O.

Every sampling routine takes its random numbers as arguments so that a path can be replayed
exactly from its counter-based random stream (see rng.py).
"""
