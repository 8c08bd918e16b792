"""Tests of the benchmark suite (``benchmarks/``) and of how ``clik bench`` finds it."""
