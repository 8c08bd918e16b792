"""Tests of :mod:`clik.bench`."""
