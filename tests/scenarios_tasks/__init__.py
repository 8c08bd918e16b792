"""Tests of the scenario keys of several tasks: ``[[tasks]]`` and ``[[objectives]]``."""
