"""Tests of the command line (:mod:`clik.cli`, :mod:`clik.demo`)."""
