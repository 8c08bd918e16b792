"""Tests of :mod:`clik.model`: robots loaded from their files, joint kinds."""
