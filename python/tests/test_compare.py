"""cosserat.compare: the rows `cosserat compare` writes to compare.csv, as records, on the
quickest case of cases/ (timoshenko_10pct: a static fixed point, FreeFEM in about a second)."""
import csv
import subprocess

import pytest

import cosserat

from conftest import ROOT, cli_binary

CASE = ROOT / "cases" / "timoshenko_10pct.toml"


def test_the_rows_are_the_cli_s_compare_csv(tmp_path):
    rows = cosserat.compare(CASE)
    run = subprocess.run([str(cli_binary()), "compare", str(CASE), "--out", str(tmp_path / "cmp")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    with open(tmp_path / "cmp" / "compare.csv") as f:
        cli = list(csv.DictReader(f))
    assert [r["quantity"] for r in rows] == [c["quantity"] for c in cli]
    assert list(rows[0]) == list(cli[0])  # the same columns, in the same order
    for r, c in zip(rows, cli):
        for k in ("rust", "freefem", "difference", "tolerance"):
            # the same numbers: the CLI writes the shortest text that reads back to the same float
            assert (r[k] is None and c[k] == "") or r[k] == float(c[k]), (r["quantity"], k)
        assert r["result"] == c["result"] and r["basis"] == c["basis"].replace("'", '"') or r["basis"] == c["basis"]
    # both engines solve the same equations: every row within its derived tolerance
    assert all(r["result"] == "pass" and r["difference"] <= r["tolerance"] for r in rows)
    tip = next(r for r in rows if r["quantity"] == "tip_y_m")
    assert tip["rust"] < 0 and abs(tip["freefem"] / tip["rust"] - 1) < 1e-8


def test_bad_requests_raise():
    with pytest.raises(ValueError, match="frames"):
        cosserat.compare(CASE, frames=0)
    with pytest.raises(RuntimeError, match="clip"):
        cosserat.compare(CASE, frames=3)  # not a clip case: --frames applies to clips only
