"""run_case(..., out=PATH) writes the folder `cosserat run CASE --out PATH` writes: the same files,
byte for byte, but for what differs between any two runs (wall times, the pid, dates: the keys
and columns scripts/check_same_outputs.sh leaves out), and the result is returned as well."""
import csv
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

import cosserat

from conftest import ROOT, cli_binary

# run.json / metrics.json keys that hold times, the process or the host (check_same_outputs.sh)
VOLATILE = re.compile(r'"([a-z_]*wall[a-z_]*|[a-z_]*unix[a-z_]*|pid|host[a-z_]*|[a-z_]*rss[a-z_]*|cpu_s)"')
TIMED_TABLES = ("frames.csv", "iterations.csv", "summary.csv")


def files(d):
    return sorted(str(p.relative_to(d)) for p in d.rglob("*") if p.is_file())


def differing(a, b):
    """The files of folders a and b that differ, as check_same_outputs.sh compares them."""
    assert files(a) == files(b)
    bad = []
    for f in files(a):
        x, y = (a / f).read_bytes(), (b / f).read_bytes()
        name = f.rsplit("/", 1)[-1]
        if name in ("run.json", "metrics.json"):
            keep = lambda t: [line for line in t.decode().splitlines() if not VOLATILE.search(line)]
            same = keep(x) == keep(y)
        elif name in TIMED_TABLES:
            ra, rb = list(csv.reader(x.decode().splitlines())), list(csv.reader(y.decode().splitlines()))
            cols = [i for i, h in enumerate(ra[0]) if not ("wall" in h or (h.endswith("_s") and "time" in h))]
            same = ra[0] == rb[0] and len(ra) == len(rb) and all(
                [r[i] for i in cols] == [s[i] for i in cols] for r, s in zip(ra[1:], rb[1:]))
        else:
            same = x == y
        if not same:
            bad.append(f)
    return bad


def cli_then_python(tmp_path, case, **kwargs):
    """The CLI's folder (moved to tmp/cli) and Python's (tmp/out: both written under one name,
    which messages name), and Python's result."""
    out = tmp_path / "out"
    extra = ["--output-format", kwargs["output_format"]] if "output_format" in kwargs else []
    run = subprocess.run([str(cli_binary()), "run", str(case), "--out", str(out), "--quiet", *extra],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    shutil.move(out, tmp_path / "cli")
    r = cosserat.run_case(case, out=out, **kwargs)
    return tmp_path / "cli", out, r


def test_a_static_case_s_folder_equals_the_cli_s(tmp_path):
    cli, py, r = cli_then_python(tmp_path, ROOT / "cases" / "timoshenko_10pct.toml")
    assert differing(cli, py) == []
    assert len(files(py)) > 3 and r["out"] == str(py)
    # the result returned is the one written
    metrics = json.loads((py / "metrics.json").read_text())
    assert r["status"] == "ok" and r["metrics"]["tip_y_m"] == metrics["tip_y_m"]


def test_a_clip_s_folder_equals_the_cli_s_and_holds_the_frames_returned(tmp_path, recording):
    x = recording["positions_m"][:5].copy()
    x[2, 10:12] = np.nan  # untracked nodes, filled alike
    np.save(tmp_path / "worm.npy", x)
    case = tmp_path / "worm.toml"
    case.write_text(cosserat.recording_case(nodes=33, frame_interval_s=0.04, file=str(tmp_path / "worm.npy")))
    cli, py, r = cli_then_python(tmp_path, case, output_format="compact")
    assert differing(cli, py) == []
    manifest = json.loads((py / "run.json").read_text())
    assert manifest["status"] == "complete" and manifest["frames_done"] == r["frames_done"] == 5
    fields = cosserat.read_compact(py)
    assert np.array_equal(fields["x_m"], r["x_m"][..., 0]) and np.array_equal(fields["z_m"], r["x_m"][..., 2])
    # an earlier run's folder is replaced; a folder of other files only when asked (--force)
    again = cosserat.run_case(case, out=py, output_format="compact")
    assert np.array_equal(again["x_m"], r["x_m"]) and differing(cli, py) == []
    foreign = tmp_path / "notes"
    foreign.mkdir()
    (foreign / "mine.txt").write_text("not a run")
    with pytest.raises(OSError, match="no run.json"):
        cosserat.run_case(case, out=foreign, output_format="compact")
    assert (foreign / "mine.txt").read_text() == "not a run"
    cosserat.run_case(case, out=foreign, force=True, output_format="compact")
    assert not (foreign / "mine.txt").exists() and (foreign / "run.json").is_file()
