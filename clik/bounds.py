"""Budgets that bound what one input may ask of clik."""

MAX_STEPS = 100_000_000
"""Largest run, ``(duration + settle) / dt + 1`` samples (about 15 minutes at 8 us per
step): a typo in ``dt`` fails at once, not as a run that never ends or an allocation
that cannot succeed."""
