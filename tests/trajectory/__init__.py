"""Tests of :mod:`clik.trajectory`."""
