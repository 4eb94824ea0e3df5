"""A reconstruction through Python equals the CLI's files for the same recording and case, to
the last bit: `cosserat run CASE --output-format compact` on the recording saved as .npy and
the case `cosserat.recording_case` writes."""
import csv
import subprocess

import numpy as np

import cosserat

from conftest import cli_binary

# fields.npz column names → (result array, component)
NODE_COLUMNS = {
    "x_m": ("x_m", 0), "y_m": ("x_m", 1), "z_m": ("x_m", 2),
    "alpha_rad": ("angles_rad", 0), "beta_rad": ("angles_rad", 1), "gamma_rad": ("angles_rad", 2),
    "d1_x": ("d1", 0), "d1_y": ("d1", 1), "d1_z": ("d1", 2),
    "d2_x": ("d2", 0), "d2_y": ("d2", 1), "d2_z": ("d2", 2),
    "d3_x": ("d3", 0), "d3_y": ("d3", 1), "d3_z": ("d3", 2),
    "f_x_n_per_m": ("f_n_per_m", 0), "f_y_n_per_m": ("f_n_per_m", 1), "f_z_n_per_m": ("f_n_per_m", 2),
    "l_x_nm_per_m": ("l_nm_per_m", 0), "l_y_nm_per_m": ("l_nm_per_m", 1), "l_z_nm_per_m": ("l_nm_per_m", 2),
    "data_x_m": ("data_m", 0), "data_y_m": ("data_m", 1), "data_z_m": ("data_m", 2),
    "omega1_rad_per_s": ("omega_rad_per_s", 0), "omega2_rad_per_s": ("omega_rad_per_s", 1),
    "omega3_rad_per_s": ("omega_rad_per_s", 2),
    "kappa1_per_m": ("kappa_per_m", 0), "kappa2_per_m": ("kappa_per_m", 1), "kappa3_per_m": ("kappa_per_m", 2),
    "n_x_n": ("n_n", 0), "n_y_n": ("n_n", 1), "n_z_n": ("n_n", 2),
    "m_x_nm": ("m_nm", 0), "m_y_nm": ("m_nm", 1), "m_z_nm": ("m_nm", 2),
    "n1_n": ("n_local_n", 0), "n2_n": ("n_local_n", 1), "n3_n": ("n_local_n", 2),
    "m1_nm": ("m_local_nm", 0), "m2_nm": ("m_local_nm", 1), "m3_nm": ("m_local_nm", 2),
}


def test_python_equals_the_cli_to_the_last_bit(tmp_path, recording):
    x = recording["positions_m"].copy()
    x[5, 20:23] = np.nan  # with untracked nodes, filled alike
    np.save(tmp_path / "worm.npy", x)
    case = tmp_path / "worm.toml"
    case.write_text(cosserat.recording_case(nodes=33, frame_interval_s=0.04, file=str(tmp_path / "worm.npy")))
    out = tmp_path / "out"
    run = subprocess.run(
        [str(cli_binary()), "run", str(case), "--out", str(out), "--output-format", "compact", "--quiet"],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stderr
    r = cosserat.reconstruct(x, frame_interval_s=0.04)
    fields = cosserat.read_compact(out)
    assert np.array_equal(fields["frame"], r["frame"])
    assert np.array_equal(fields["s_m"][0], r["s_m"]) and np.array_equal(fields["s_mid_m"][0], r["s_mid_m"])
    compared = 0
    for column, (name, k) in NODE_COLUMNS.items():
        cli, py = fields[column], r[name][..., k]
        assert cli.shape == py.shape, column
        # the same bits: equal as integers of their IEEE representation
        assert np.array_equal(cli.view(np.uint64), py.view(np.uint64)), column
        compared += cli.size
    assert compared == 12 * (27 * 33 + 15 * 32)
    # frames.csv: every number as the CLI prints it ({:.10e}, integers and flags as integers)
    with open(out / "frames.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 12
    for column, values in r["frames"].items():
        for row, v in zip(rows, values):
            text = row[column]
            if values.dtype.kind in "bi":
                assert int(text) == int(v), column
            else:
                assert float(text) == float(f"{v:.10e}") or (np.isnan(v) and text.lower() == "nan"), column
    # run.json's chosen weights are the result's
    import json

    manifest = json.loads((out / "run.json").read_text())
    assert json.dumps(manifest).count(repr(r["lambda_g"])) >= 1
