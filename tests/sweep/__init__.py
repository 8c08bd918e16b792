"""Tests of :mod:`clik.sweep` (sweeps and reachability maps)."""
