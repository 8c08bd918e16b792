"""`clik bench` finds the suite in a checkout, and says how to get one when there is none."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import clik
from clik.cli import main
from clik.commands import bench
from clik.errors import ClikError

ROOT = Path(__file__).resolve().parents[2]


def installed_elsewhere(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """Pretend clik was imported from a site-packages folder with no suite beside it."""
    site = tmp_path / "site-packages"
    (site / "clik").mkdir(parents=True)
    monkeypatch.setattr(clik, "__file__", str(site / "clik" / "__init__.py"))
    return site


def test_the_checkout_clik_runs_from_is_found():
    assert bench.is_checkout(ROOT)
    assert bench.candidates()[0] == ROOT
    assert bench.find_checkout() == ROOT


def test_without_the_package_s_checkout_the_working_folder_is_used(tmp_path, monkeypatch):
    site = installed_elsewhere(monkeypatch, tmp_path)
    monkeypatch.chdir(ROOT)
    assert bench.candidates() == [site, ROOT]
    assert bench.find_checkout() == ROOT


def test_without_a_checkout_clik_bench_says_how_to_get_one(tmp_path, monkeypatch, capsys):
    site = installed_elsewhere(monkeypatch, tmp_path)
    elsewhere = tmp_path / "work"
    (elsewhere / "benchmarks").mkdir(parents=True)  # a folder of that name is not a checkout
    (elsewhere / "benchmarks" / "suite.py").write_text("")
    monkeypatch.chdir(elsewhere)
    assert main(["bench", "--quick", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("clik: error: clik bench runs the benchmark suite of a clik checkout")
    assert f"none found in {site} nor in {elsewhere}." in err
    assert "pip install -e '.[bench]'" in err and "python -m benchmarks" in err
    assert not (tmp_path / "out").exists()
    with pytest.raises(ClikError) as caught:
        bench.find_checkout()
    assert caught.value.exit_code == 2


def test_another_package_named_benchmarks_is_refused(tmp_path, monkeypatch):
    """The suite already imported comes from this checkout, not from the one asked for."""
    other = tmp_path / "other"
    for part in ("clik", "benchmarks"):
        (other / part).mkdir(parents=True)
        (other / part / "__init__.py").write_text('"""Not clik\'s."""\n')
    (other / "benchmarks" / "suite.py").write_text("")
    monkeypatch.setattr(sys, "path", list(sys.path))
    import benchmarks.suite  # noqa: F401  (this checkout's, as the tests import it)

    with pytest.raises(ClikError, match="is not the checkout's suite"):
        bench.load_suite(other)
    assert bench.load_suite(ROOT).__name__ == "benchmarks.suite"


def test_python_m_benchmarks_from_the_checkout_root():
    done = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--help"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "python -m benchmarks" in done.stdout and "--quick" in done.stdout


def test_clik_imports_without_the_suite_nor_its_peers():
    """``import clik`` and its command line, with benchmarks, pink and mink unimportable."""
    code = (
        "import sys\n"
        "for name in ('benchmarks', 'pink', 'mink'):\n"
        "    sys.modules[name] = None\n"
        "import clik, clik.cli\n"
        "clik.cli.parser()\n"
        "print(sorted(m for m in sys.modules if m.startswith(('benchmarks.', 'pink.', 'mink.'))))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False, cwd=ROOT
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"
