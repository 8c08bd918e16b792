"""Tests of :mod:`clik.tasks`."""
