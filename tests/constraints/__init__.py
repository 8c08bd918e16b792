"""Tests of :mod:`clik.constraints` (and ``src/engine/constraints``)."""
