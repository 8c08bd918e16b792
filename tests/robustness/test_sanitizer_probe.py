"""``make sanitize``'s self-check: a planted UBSan or ASan report (``clik._sanitize_probe``).

Skipped unless ``CLIK_PLANT_SANITIZER`` is ``ubsan`` or ``asan``: ``make sanitize`` runs this
file once with each, under the sanitizers, before its tests, and fails unless the planted
report fails that run and shows in its log (``.ci/sanitize-pytest --planted``). The probe
module is built only into the sanitizer build (``-DCLIK_SANITIZE_PROBE=ON``).
"""

from __future__ import annotations

import importlib
import os

import pytest

PLANT = os.environ.get("CLIK_PLANT_SANITIZER", "")

pytestmark = pytest.mark.skipif(
    not PLANT, reason="make sanitize's planted report (set CLIK_PLANT_SANITIZER=ubsan|asan)"
)


def test_planted_report():
    # Imported here: a missing probe fails the run (the self-check then says the report
    # did not show) instead of skipping it.
    probe = importlib.import_module("clik._sanitize_probe")
    if PLANT == "ubsan":
        probe.signed_overflow(1)  # INT_MAX + 1: UBSan's "signed integer overflow"
    elif PLANT == "asan":
        probe.heap_overflow_read(4)  # one past a 4-int heap array: ASan ends the process
    else:
        pytest.fail(f"CLIK_PLANT_SANITIZER={PLANT!r}: expected 'ubsan' or 'asan'")
