"""Tests of scenario files' keys that :mod:`clik.scenarios` reads and builds."""
