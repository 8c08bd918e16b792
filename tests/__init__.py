"""clik's tests, one folder per room of ``clik/``; helpers and ``data/`` at this level."""
