"""The archive and its modelDescription.xml, checked by two independent tools."""

import pathlib
import subprocess
import sys
import zipfile

from fmpy.validation import validate_fmu


def test_fmpy_validate_reports_nothing(fmu_path):
    problems = validate_fmu(fmu_path)
    assert problems == [], problems


def test_fmutool_check_passes(fmu_path):
    fmutool = pathlib.Path(sys.executable).parent / "fmutool"
    run = subprocess.run([str(fmutool), "-input", fmu_path, "-check"], capture_output=True, text=True)
    out = run.stdout + run.stderr
    assert run.returncode == 0, out
    assert "seems to be compliant with FMI-2.0" in out, out
    assert "No semantic error" in out, out
    assert not any(line.startswith(("ERROR", "CRITICAL")) for line in out.splitlines()), out


def test_archive_layout(fmu_path, md):
    names = set(zipfile.ZipFile(fmu_path).namelist())
    assert "modelDescription.xml" in names
    assert f"binaries/linux64/{md.coSimulation.modelIdentifier}.so" in names
    assert "documentation/index.html" in names


def test_only_fmi_symbols_exported_and_only_libc_needed(unzipped, md):
    """The binary serves the FMI 2.0 and the FMI 3.0 FMU: it exports fmi2* and fmi3* functions and
    nothing else."""
    so = pathlib.Path(unzipped) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    nm = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True)
    symbols = [line.split()[-1] for line in nm.stdout.splitlines() if line.split()[-2] in ("T", "W")]
    assert symbols, nm.stdout
    assert all(s.startswith(("fmi2", "fmi3")) for s in symbols), [s for s in symbols if not s.startswith(("fmi2", "fmi3"))]
    for f in ["fmi2Instantiate", "fmi2DoStep", "fmi2SerializeFMUstate", "fmi2GetRealStatus", "fmi2CancelStep",
              "fmi3InstantiateCoSimulation", "fmi3DoStep", "fmi3SerializeFMUState", "fmi3GetFloat64"]:
        assert f in symbols
    ldd = subprocess.run(["ldd", str(so)], capture_output=True, text=True, check=True).stdout
    allowed = ("linux-vdso", "libc.so", "libm.so", "libgcc_s.so", "ld-linux", "libpthread", "libdl")
    extra = [l for l in ldd.splitlines() if l.strip() and not any(a in l for a in allowed)]
    assert extra == [], ldd
