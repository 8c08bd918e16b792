"""``python -m benchmarks --out DIR [--quick] [--quiet]``: run the suite and print ``bench.md``."""

from benchmarks.suite import main

if __name__ == "__main__":  # imported (e.g. by pkgutil.walk_packages): do nothing
    main()
