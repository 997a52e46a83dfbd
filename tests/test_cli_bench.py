"""``embodichain bench`` runs a benchmark script of the checkout with the given args."""

import os

from embodichain_core.cli import bench


def test_runs_the_named_script_with_its_arguments(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "benchmarks"
    folder.mkdir()
    (folder / "env_throughput.py").write_text("import sys\nprint('args', sys.argv[1:])\nsys.exit(3)\n")
    monkeypatch.chdir(tmp_path)
    assert bench.main(["env", "--quick", "--num-envs", "2"]) == 3
    assert "args ['--quick', '--num-envs', '2']" in capsys.readouterr().out


def test_outside_a_checkout_says_so(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bench, "find_benchmarks", lambda: None)
    assert bench.main(["ik"]) == 2
    assert "source checkout" in capsys.readouterr().err


def test_finds_this_checkouts_benchmarks():
    assert os.path.isfile(os.path.join(bench.find_benchmarks(), "env_throughput.py"))
