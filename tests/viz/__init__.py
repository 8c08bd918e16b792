"""Tests of :mod:`clik.viz` (with and without a browser)."""
