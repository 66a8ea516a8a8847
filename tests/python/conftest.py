"""Shared fixtures of the import-side tests: the packaged FMU, low-level instances with a logger
that records every message, the named parameter sets (`hsp presets --json`), and the analytic
closed-loop response of the LOES (eq. 1, eq. 2)."""

import ctypes
import functools
import json
import math
import os
import pathlib
import shutil
import subprocess
import tempfile
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import scipy.linalg
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU = ROOT / "fmu" / "HydraulicSlewingPlate.fmu"


def hsp(*args):
    """Runs `hsp` built from the checkout's sources (cargo rebuilds it when they changed)."""
    return subprocess.run(["cargo", "run", "--release", "--quiet", "--bin", "hsp", "--", *args],
                          cwd=ROOT, capture_output=True, text=True, check=True).stdout


def packaged_source_hash(path, platform="linux64"):
    """The source hash the FMU's Linux binary carries (`hsp-source-hash:<hash>`, written by
    build.rs; `hsp source-hash` prints the checkout's), or None. `platform` is the binaries folder:
    linux64 in FMI 2.0, x86_64-linux in FMI 3.0."""
    try:
        with zipfile.ZipFile(path) as z:
            binary = z.read(f"binaries/{platform}/HydraulicSlewingPlate.so")
    except (OSError, KeyError, zipfile.BadZipFile):
        return None
    prefix = b"hsp-source-hash:"
    at = binary.find(prefix)
    return None if at < 0 else binary[at + len(prefix):at + len(prefix) + 16].decode()


@pytest.fixture(scope="session")
def fmu_path():
    """The packaged FMU, built from the checkout's sources: the test command builds it before
    pytest runs; a missing or stale one (its binary's source hash differs from the checkout's)
    is rebuilt here with `hsp package`."""
    this = hsp("source-hash").strip()
    if packaged_source_hash(FMU) != this:
        hsp("package")
    found = packaged_source_hash(FMU)
    assert found == this, f"{FMU} carries source hash {found}, the checkout {this}"
    return str(FMU)


@pytest.fixture(scope="session")
def unzipped(fmu_path):
    d = extract(fmu_path)
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="session")
def md(fmu_path):
    return read_model_description(fmu_path)


@pytest.fixture(scope="session")
def vr(md):
    return {v.name: v.valueReference for v in md.modelVariables}


SSV_NS = {"ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}


def read_ssv(text):
    """An SSP parameter set (.ssv) as {name: value}, each value typed by its ssv element."""
    root = ET.fromstring(text)
    cast = {"Real": float, "Integer": int, "Boolean": lambda v: v == "true"}
    values = {}
    for p in root.iterfind("ssv:Parameters/ssv:Parameter", SSV_NS):
        (typed,) = list(p)
        kind = typed.tag.split("}")[1]
        values[p.get("name")] = cast[kind](typed.get("value"))
    return values


@functools.lru_cache(maxsize=None)
def _presets():
    return {p["name"]: p["settings"] for p in json.loads(hsp("presets", "--json"))}


def preset(name, **extra):
    """The start values of a named parameter set (src/model/presets.rs, the one definition), with
    `extra` start values (names with dots as keyword arguments: pass a dict with **{...})."""
    return {**_presets()[name], **extra}


def set_values(slave, md, values):
    """Sets `values` ({name: value}) on a low-level instance, each with its variable's type (an
    Enumeration as an Integer, as FMI 2.0 does)."""
    kinds = {v.name: (v.type, v.valueReference) for v in md.modelVariables}
    for var, value in values.items():
        kind, ref = kinds[var]
        {"Real": slave.setReal, "Integer": slave.setInteger, "Enumeration": slave.setInteger,
         "Boolean": slave.setBoolean}[kind]([ref], [value])


def apply_preset(slave, md, name):
    """Sets a preset on a low-level instance (before initialisation), each value with its type."""
    set_values(slave, md, _presets()[name])


class Recorder:
    """Keeps every log message of an instance: (status, category, message)."""

    def __init__(self):
        self.messages = []

    def text(self):
        return "\n".join(m for _, _, m in self.messages)


def make_slave(md, unzipped, name="test", logging_on=False, guid=None):
    """An instantiated FMU2Slave whose log messages are recorded in slave.recorder."""
    recorder = Recorder()

    def log(env, instance, status, category, message):
        recorder.messages.append((status, category.decode(), message.decode().replace("%%", "%")))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, s: None)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: None)
    slave = FMU2Slave(guid=guid or md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    slave.recorder = recorder
    slave._keep_callbacks = callbacks  # ctypes callbacks must outlive the instance
    slave.instantiate(callbacks=callbacks, loggingOn=logging_on)
    return slave


@pytest.fixture
def slave_factory(md, unzipped):
    made = []

    def factory(**kw):
        s = make_slave(md, unzipped, **kw)
        made.append(s)
        return s

    yield factory
    for s in made:
        try:
            s.freeInstance()
        except Exception:
            pass


# The LOES default parameters (docs/model-notes.md, item 7): the printed C3 and I_b, the rest
# fitted to G_est(s) = 2.25e6 / (s (s + 65) (s + 753)) of eq. 2.
C3, I_B, A1, A2 = 5.28e-11, 0.0025, 2.0, 10.0
R7 = 1 / (818 * C3)
D_M = math.sqrt(48945 * C3 * I_B)
K_POT = 10 / math.radians(150)
K_SV = 2.25e6 * C3 * I_B / (A1 * A2 * D_M * K_POT)


def closed_loop_step(times, r=1.0, c3=C3, i_b=I_B, r7=R7, d_m=D_M, k_sv=K_SV, a1=A1, a2=A2, k_pot=K_POT):
    """y_pot(t) for a step r at t = 0 of the unity-feedback loop around
    G(s) = K / (s (s^2 + s/(R7 C3) + D_m^2/(C3 I_b))), K = k_pot A1 A2 k_sv D_m / (C3 I_b):
    the companion form of G/(1+G), evaluated exactly with a matrix exponential."""
    K = k_pot * a1 * a2 * k_sv * d_m / (c3 * i_b)
    a2c, a1c = 1 / (r7 * c3), d_m ** 2 / (c3 * i_b)
    A = np.array([[0, 1, 0], [0, 0, 1], [-K, -a1c, -a2c]], dtype=float)
    B = np.array([0, 0, K * r])
    C = np.array([1.0, 0, 0])
    M = np.zeros((4, 4))
    M[:3, :3] = A
    M[:3, 3] = B
    out = []
    for t in times:
        E = scipy.linalg.expm(M * t)
        out.append(C @ E[:3, 3])
    return np.array(out)


def page_requests(net_log):
    """The URLs the page itself requested over the network, from Chromium's net log: requests
    whose network isolation key is the page's (file://) site; the browser's own background
    requests carry none. (Checked by hand: an <img> pointing at an https address shows up here.)"""
    events = json.loads(pathlib.Path(net_log).read_text())["events"]
    urls, from_page = {}, set()
    for e in events:
        p, source = e.get("params", {}), e.get("source", {}).get("id")
        if "url" in p:
            urls.setdefault(source, p["url"])
        if "file://" in str(p.get("network_isolation_key", "")):
            from_page.add(source)
    return sorted({urls[s] for s in from_page if s in urls})
