"""Tests of :mod:`clik.solving` (and ``src/engine/solving``)."""
