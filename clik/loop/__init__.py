"""The tracking loop: the closed-loop law integrated along a reference, sample by sample.

``tracker`` holds ``Tracker`` and ``track`` (settings and inputs checked once);
``tracking`` is one run, the specification (``_Run.samples``);
``compiled_run`` hands the same samples to the compiled engine (``clik._engine``,
``src/engine/loop/``). Around the step: the laws (``laws``) and their gains
(``gains``), the reference sampled chunk by chunk (``reference_stream``), the
stop checks (``stop_checks``), the record (``recording``) and the limits
crossed (``violations``). What a run returns is in :mod:`clik.outputs`.
"""
