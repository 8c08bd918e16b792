"""Budgets that bound what one input may ask of clik."""

MAX_COORDINATE = 1000.0
"""Largest absolute position or size [m] (1 km): a URDF origin, a mesh's scaled vertices,
a scenario's positions, lengths and thresholds."""

SCALE_RANGE = (1e-6, 1e6)
"""Accepted range of the absolute value of each mesh scale factor (URDF and scenario)."""

MAX_STEPS = 100_000_000
"""Largest run, ``(duration + settle) / dt + 1`` samples (about 15 minutes at 8 us per
step): a typo in ``dt`` fails at once, not as a run that never ends or an allocation
that cannot succeed."""

MAX_RECORD_BYTES = 512 * 2**20
"""Largest memory for a run's record (the arrays of its kept samples) [bytes]: a long run
keeps every ``record_every``-th sample within it (a million samples of a 7-joint arm
with obstacles take about 400 MB)."""
