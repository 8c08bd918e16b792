"""Tests of :mod:`clik.speed`."""
