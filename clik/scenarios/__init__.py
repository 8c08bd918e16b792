"""Scenario files shipped with clik: the paper's case study (METHOD.md), for laws (9) and (10)."""
