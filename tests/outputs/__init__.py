"""Tests of :mod:`clik.outputs`."""
