"""Whole-package hardening: bad input, hostile files and sizes, the robot zoo."""
