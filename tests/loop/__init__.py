"""Tests of :mod:`clik.loop` (and the compiled loop, ``src/engine/loop``)."""
