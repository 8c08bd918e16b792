"""``python -m clik.bench --out DIR [--quick]``: run the suite and print ``bench.md``."""

from clik.bench.suite import main

if __name__ == "__main__":  # imported (e.g. by pkgutil.walk_packages): do nothing
    main()
