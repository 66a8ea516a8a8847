"""tools/identify_dask.py: the starts of `hsp identify --starts N` as Dask tasks on a LocalCluster of
2 worker processes give the same output as the starts on hsp's own threads, to the bit, with the
data files sent to the workers (not read from their paths there); a start's failure reaches the
user with hsp's message."""

import importlib.util
import json
import pathlib
import subprocess
import sys

import numpy as np

from conftest import hsp

ROOT = pathlib.Path(__file__).resolve().parents[2]
HSP = ROOT / "target" / "release" / "hsp"
spec = importlib.util.spec_from_file_location("identify_dask", ROOT / "tools" / "identify_dask.py")
identify_dask = importlib.util.module_from_spec(spec)
spec.loader.exec_module(identify_dask)


def response(tmp_path, output):
    """The response from r to `output` at the FMU's start values, 60 points, as hsp identify's
    CSV in `tmp_path`."""
    h = json.loads(hsp("frf", "--json", "--input", "r", "--output", output, "--points", "60"))
    f = np.array(h["f_hz"])
    c = np.array(h["magnitude"]) * np.exp(1j * np.radians(h["phase_deg"]))
    path = tmp_path / f"{output}.csv"
    path.write_text("f_Hz,re,im\n" + "".join(f"{float(a)!r},{float(b.real)!r},{float(b.imag)!r}\n"
                                            for a, b in zip(f, c)))
    return path


def test_the_starts_on_dask_give_the_threads_result_to_the_bit(tmp_path):
    data = response(tmp_path, "acc_tip")
    args = ["--frf", f"r:acc_tip:{data}", "--fit", "plate.E:1e10:4e11",
            "--set", "plate.E=2e11", "--max-iterations", "30", "--json"]
    starts = ["--starts", "4", "--seed", "3"]
    threads = subprocess.run([str(HSP), "identify", *args, *starts], capture_output=True,
                             text=True, check=True).stdout
    # The workers get the data, not its path: the file is moved away before the tasks run.
    moved = tmp_path / "elsewhere.csv"
    data.rename(moved)
    args_moved = [a.replace(str(data), str(moved)) for a in args]
    out = subprocess.run([sys.executable, str(ROOT / "tools" / "identify_dask.py"), *starts,
                          "--workers", "2", "--hsp", str(HSP), "--", *args_moved],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    a, b = json.loads(threads), json.loads(out.stdout)
    assert len(b["starts"]) == 4 and b["minima"]
    # The model evaluations and exact derivatives counted here are this process's: the starts
    # ran elsewhere.
    assert b.pop("evaluations") < a.pop("evaluations")
    assert b.pop("derivatives") < a.pop("derivatives")
    # and the data file is named where it now is.
    a["responses"][0]["file"] = str(moved)
    assert a == b, "the Dask starts differ from the threads'"


def test_a_bad_argument_reaches_the_user_with_hsps_message(tmp_path):
    data = response(tmp_path, "y_pot")
    out = subprocess.run([sys.executable, str(ROOT / "tools" / "identify_dask.py"),
                          "--starts", "2", "--workers", "1", "--hsp", str(HSP), "--",
                          "--frf", f"r:y_pot:{data}", "--fit", "no.such:1:2"],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode != 0
    assert "no.such" in out.stderr


def test_the_data_files_are_found_in_the_arguments():
    args, files = identify_dask.split_data(
        ["--frf", f"r:y_pot:{__file__}", f"--series={__file__}", "--fit", "plate.zeta"])
    assert args == ["--frf", "r:y_pot:{data0}", "--series", "{data1}", "--fit", "plate.zeta"]
    name = pathlib.Path(__file__).name
    assert files["{data0}"] == (name, pathlib.Path(__file__).read_bytes()) == files["{data1}"]
