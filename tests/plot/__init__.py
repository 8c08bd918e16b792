"""Tests of :mod:`clik.plot`."""
