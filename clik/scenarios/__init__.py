"""Scenario files shipped with clik: the case study of docs/method.md, laws (9) and (10)."""
